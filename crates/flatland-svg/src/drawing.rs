//! [`Drawing`]: what an import gives — a validated scene, the marked lights, the warnings and
//! counts — and how the importer's findings become one.

use std::collections::{BTreeSet, HashMap};

use flatland_geom::{DVec2, Edge, EdgeId, GeomError, PointLight, Scene};

use crate::source::Source;
use crate::{ElementName, Skipped, SvgError, Warning, WarningKind};

/// A circle marked as a point light (class `flatland-light`).
#[derive(Clone, Debug, PartialEq)]
pub struct MarkedLight {
    /// The circle.
    pub element: ElementName,
    /// Its centre, in plan coordinates.
    pub at: DVec2,
    /// Its power (`data-flatland-power`, default 1).
    pub power: f64,
}

/// An imported drawing: its edges as a validated [`Scene`] (in plan units, y up), the element
/// each edge came from, the marked lights, and what was skipped or odd.
#[derive(Clone, Debug)]
pub struct Drawing {
    scene: Scene,
    /// Per edge, its element's index in `names`.
    source_of: Vec<usize>,
    names: Vec<ElementName>,
    lights: Vec<MarkedLight>,
    warnings: Vec<Warning>,
    skipped: Skipped,
}

impl Drawing {
    /// The edges, validated. The marked lights are not in it ([`Drawing::into_scene`]).
    #[must_use]
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The element edge `id` came from.
    ///
    /// # Panics
    /// If `id` is not an edge of [`Drawing::scene`].
    #[must_use]
    pub fn element_of(&self, id: EdgeId) -> &ElementName {
        &self.names[self.source_of[id.index()]]
    }

    /// The circles marked as point lights, in document order.
    #[must_use]
    pub fn lights(&self) -> &[MarkedLight] {
        &self.lights
    }

    /// What the import skipped or found odd, one line each, in document order (the drawing's
    /// own warnings last).
    #[must_use]
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// How many elements were skipped, by reason.
    #[must_use]
    pub fn skipped(&self) -> Skipped {
        self.skipped
    }

    /// The scene to light: the edges with the marked circles as its point lights. A light
    /// the scene refuses (on a wall, a power that is not finite) is an error naming its circle.
    pub fn into_scene(self) -> Result<Scene, SvgError> {
        let lights = self
            .lights
            .iter()
            .map(|l| PointLight::new(l.at, l.power))
            .collect();
        self.scene.with_lights(lights).map_err(|error| {
            let light = match &error {
                GeomError::LightNonFinite { light, .. }
                | GeomError::LightPower { light, .. }
                | GeomError::LightOnEdge { light, .. } => Some(*light),
                _ => None,
            };
            match light.and_then(|i| self.lights.get(i)) {
                Some(marked) => SvgError::Light {
                    element: marked.element.clone(),
                    error: Box::new(error),
                },
                None => SvgError::Scene {
                    error: Box::new(error),
                },
            }
        })
    }
}

/// The importer's findings so far.
pub(crate) struct Pending {
    edges: Vec<Edge>,
    source_of: Vec<usize>,
    /// Per edge, whether it faces out of a fill (a candidate hidden face).
    from_fill: Vec<bool>,
    pub lights: Vec<MarkedLight>,
    warnings: Vec<(usize, WarningKind)>,
    pub skipped: Skipped,
    /// Per element, whether usvg drew it (a path of it was met).
    pub drawn: Vec<bool>,
}

impl Pending {
    pub fn new(source: &Source) -> Pending {
        Pending {
            edges: Vec::new(),
            source_of: Vec::new(),
            from_fill: Vec::new(),
            lights: Vec::new(),
            warnings: Vec::new(),
            skipped: Skipped::default(),
            drawn: vec![false; source.elements.len()],
        }
        .with_warnings(&source.warnings)
    }

    fn with_warnings(mut self, warnings: &[(usize, WarningKind)]) -> Pending {
        self.warnings.extend(warnings.iter().cloned());
        self
    }

    pub fn push(&mut self, edge: Edge, element: usize, from_fill: bool) {
        self.edges.push(edge);
        self.source_of.push(element);
        self.from_fill.push(from_fill);
    }

    pub fn warn(&mut self, element: usize, kind: WarningKind) {
        self.warnings.push((element, kind));
    }

    /// Warns about `element` and counts it where `count` says.
    pub fn skip(
        &mut self,
        element: usize,
        kind: WarningKind,
        count: fn(&mut Skipped) -> &mut usize,
    ) {
        *count(&mut self.skipped) += 1;
        self.warn(element, kind);
    }

    /// The drawing: hidden faces removed, the scene validated, the drawing's own checks done.
    pub fn finish(mut self, source: &Source) -> Result<Drawing, SvgError> {
        for (e, element) in source.elements.iter().enumerate() {
            if element.drawn_here && !self.drawn[e] && element.own.role.is_none() {
                self.skip(e, WarningKind::NotDrawn, |s| &mut s.not_drawn);
            }
        }
        self.remove_hidden_faces();
        self.skipped.texts = source.texts.len();
        self.skipped.images = source.images.len();
        let names: Vec<ElementName> = source.elements.iter().map(|e| e.name.clone()).collect();
        let scene = Scene::new(std::mem::take(&mut self.edges))
            .map_err(|error| self.scene_error(error, &names))?;
        self.warnings.sort_by_key(|&(e, _)| e);
        let mut warnings: Vec<Warning> = self
            .warnings
            .drain(..)
            .map(|(e, kind)| Warning {
                element: Some(names[e].clone()),
                kind,
            })
            .collect();
        warnings.extend(overlaps(&scene, &self.source_of, &names));
        for (list, kind) in [
            (&source.texts, WarningKind::Text),
            (&source.images, WarningKind::Image),
        ] {
            warnings.extend(list.iter().map(|name| Warning {
                element: Some(name.clone()),
                kind: kind.clone(),
            }));
        }
        if self.skipped.unsourced > 0 {
            warnings.push(Warning {
                element: None,
                kind: WarningKind::Unsourced {
                    paths: self.skipped.unsourced,
                },
            });
        }
        if scene.max_emission() == 0.0 && self.lights.is_empty() {
            warnings.push(Warning {
                element: None,
                kind: WarningKind::NothingLights,
            });
        }
        Ok(Drawing {
            scene,
            source_of: self.source_of,
            names,
            lights: self.lights,
            warnings,
            skipped: self.skipped,
        })
    }

    /// Removes the pairs of fill faces that lie back to back with the same end points: each
    /// faces into the other's fill, where no light reaches.
    fn remove_hidden_faces(&mut self) {
        let key = |a: DVec2, b: DVec2| (a.x.to_bits(), a.y.to_bits(), b.x.to_bits(), b.y.to_bits());
        let mut open: HashMap<(u64, u64, u64, u64), Vec<usize>> = HashMap::new();
        let mut gone = vec![false; self.edges.len()];
        for (i, e) in self.edges.iter().enumerate() {
            if !self.from_fill[i] {
                continue;
            }
            let twin = open.get_mut(&key(e.b, e.a)).and_then(|list| {
                let k = list
                    .iter()
                    .position(|&j| self.source_of[j] != self.source_of[i])?;
                Some(list.swap_remove(k))
            });
            match twin {
                Some(j) => (gone[i], gone[j]) = (true, true),
                None => open.entry(key(e.a, e.b)).or_default().push(i),
            }
        }
        let removed = gone.iter().filter(|&&g| g).count();
        if removed == 0 {
            return;
        }
        self.skipped.hidden_faces = removed;
        self.edges = kept(&self.edges, &gone);
        self.source_of = kept(&self.source_of, &gone);
        self.from_fill = kept(&self.from_fill, &gone);
    }

    fn scene_error(&self, error: GeomError, names: &[ElementName]) -> SvgError {
        let edge = match &error {
            GeomError::NoSurface { edges } => {
                return SvgError::NoSurface {
                    edges: *edges,
                    skipped: self.skipped.to_string(),
                };
            }
            GeomError::NonFinite { edge, .. }
            | GeomError::ZeroLength { edge, .. }
            | GeomError::Reflectance { edge, .. }
            | GeomError::Emission { edge, .. }
            | GeomError::TwoSidedSurface { edge } => *edge,
            _ => {
                return SvgError::Scene {
                    error: Box::new(error),
                };
            }
        };
        let element = names[self.source_of[edge]].clone();
        SvgError::Edge {
            element,
            error: Box::new(error),
        }
    }
}

fn kept<T: Copy>(items: &[T], gone: &[bool]) -> Vec<T> {
    items
        .iter()
        .zip(gone)
        .filter(|&(_, &g)| !g)
        .map(|(&x, _)| x)
        .collect()
}

/// One warning per pair of elements whose surfaces overlap (the scene's check, `O(n log n)`).
fn overlaps(scene: &Scene, source_of: &[usize], names: &[ElementName]) -> Vec<Warning> {
    let pairs: BTreeSet<(usize, usize)> = scene
        .overlapping_surface_edges()
        .into_iter()
        .map(|(i, j)| {
            let (a, b) = (source_of[i.index()], source_of[j.index()]);
            (a.min(b), a.max(b))
        })
        .collect();
    pairs
        .into_iter()
        .map(|(a, b)| Warning {
            element: Some(names[a].clone()),
            kind: WarningKind::Overlaps {
                other: names[b].clone(),
            },
        })
        .collect()
}
