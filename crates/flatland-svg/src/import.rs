//! The importer: usvg's tree of a drawing walked into edges, lights, warnings and counts.

use std::path::Path;

use flatland_geom::{DVec2, Edge};
use kurbo::Affine;
use usvg::{FillRule, Node};

use crate::attributes::{ElementRole, Faces, Material};
use crate::drawing::{Drawing, MarkedLight, Pending};
use crate::faces::{FillProblem, collinear, fill_edges};
use crate::outline::{Outline, outline, widen};
use crate::source::{self, Source};
use crate::{ImportParams, SvgError, WarningKind};

/// The default flattening tolerance, as a share of the drawing's diagonal.
const DEFAULT_FLATTEN: f64 = 1e-3;

/// Reads an SVG drawing into a [`Drawing`]: its edges as a validated scene, its marked lights,
/// and warnings naming what was skipped or odd. The crate docs describe the rules.
pub fn import(bytes: &[u8], params: &ImportParams) -> Result<Drawing, SvgError> {
    params.check()?;
    let source = source::read(bytes)?;
    let root = root_transform(&source);
    let size = source.tree.size();
    let diagonal = (root.inverse()
        * kurbo::Point::new(f64::from(size.width()), f64::from(size.height()))
        - root.inverse() * kurbo::Point::ORIGIN)
        .hypot();
    let flatten = params.flatten.unwrap_or(DEFAULT_FLATTEN * diagonal) * params.unit;
    let mut walk = Walk {
        source: &source,
        flatten,
        pending: Pending::new(&source),
    };
    // Plan = unit × (x, −y) in the root's user units.
    let to_plan = Affine::new([params.unit, 0.0, 0.0, -params.unit, 0.0, 0.0]);
    let top = Context {
        material: Material::root(params.reflectance),
        instance: None,
        to_plan,
    };
    walk.group(source.tree.root(), top);
    walk.pending.finish(&source)
}

/// [`import`] of a file; errors name the file.
pub fn import_file(path: impl AsRef<Path>, params: &ImportParams) -> Result<Drawing, SvgError> {
    let path = path.as_ref();
    std::fs::read(path)
        .map_err(SvgError::from)
        .and_then(|bytes| import(&bytes, params))
        .map_err(|e| e.in_file(path))
}

/// The root's transform (its viewBox mapping and `transform`), in f32: the transform usvg gave
/// the empty group placed first in the root.
fn root_transform(source: &Source) -> Affine {
    match source.tree.node_by_id(&source.origin_id) {
        Some(Node::Group(g)) if is_invertible(affine(g.abs_transform())) => {
            affine(g.abs_transform())
        }
        _ => Affine::IDENTITY,
    }
}

fn is_invertible(a: Affine) -> bool {
    let d = a.determinant();
    d.is_finite() && d != 0.0
}

/// A usvg transform in f64, its numbers as the drawing wrote them.
fn affine(t: usvg::Transform) -> Affine {
    let c = [t.sx, t.ky, t.kx, t.sy, t.tx, t.ty].map(widen);
    Affine::new(c)
}

struct Walk<'a> {
    source: &'a Source,
    flatten: f64,
    pending: Pending,
}

/// What a group passes down to its children.
#[derive(Clone, Copy)]
struct Context {
    material: Material,
    /// The innermost `use` (usvg drops the ids of what a `use` copies, so the `use` names
    /// those paths).
    instance: Option<usize>,
    /// From the group's coordinates to the plan, composed in f64 from each group's own
    /// transform (usvg's absolute transforms are products in f32, off by rounding).
    to_plan: Affine,
}

impl Walk<'_> {
    /// Walks the children of `group`, whose context is `context`.
    fn group(&mut self, group: &usvg::Group, context: Context) {
        for child in group.children() {
            match child {
                Node::Group(g) => {
                    let mut inner = context;
                    // The group usvg wraps the root's content in holds the root's transform:
                    // the plan is in the root's user units, inside it.
                    if !self.wraps_root(g) {
                        inner.to_plan = context.to_plan * affine(g.transform());
                    }
                    if let Some(&e) = self.source.by_id.get(g.id()) {
                        let element = &self.source.elements[e];
                        inner.material = inner.material.with(&element.own);
                        if element.name.tag == "use" {
                            inner.instance = Some(e);
                            if let Some(r) = element.referenced {
                                inner.material = inner.material.with(&self.source.elements[r].own);
                            }
                        }
                    }
                    self.group(g, inner);
                }
                Node::Path(p) => self.path(p, context),
                // Counted from the document: text and images are skipped wherever they are.
                Node::Image(_) | Node::Text(_) => {}
            }
        }
    }

    fn wraps_root(&self, g: &usvg::Group) -> bool {
        matches!(g.children().first(), Some(Node::Group(o)) if o.id() == self.source.origin_id)
    }

    fn path(&mut self, path: &usvg::Path, context: Context) {
        let own = self.source.by_id.get(path.id()).copied();
        let Some(element) = own.or(context.instance) else {
            self.pending.skipped.unsourced += 1;
            return;
        };
        self.pending.drawn[element] = true;
        let (material, light) = match own {
            Some(e) => {
                let attributes = &self.source.elements[e].own;
                (context.material.with(attributes), attributes.light)
            }
            // Inside a `use`: the marked circle it refers to is a light.
            None => {
                let referenced = self.source.elements[element].referenced;
                let light = referenced.and_then(|r| self.source.elements[r].own.light);
                (context.material, light)
            }
        };
        if material.role == ElementRole::Ignore {
            self.pending.skipped.ignored += 1;
        } else if !path.is_visible() {
            self.pending
                .skip(element, WarningKind::Hidden, |s| &mut s.hidden);
        } else if let Some(power) = light {
            self.light(path, element, power, context.to_plan);
        } else {
            match outline(path.data(), context.to_plan, self.flatten) {
                Err(_) => self
                    .pending
                    .skip(element, WarningKind::NonFinite, |s| &mut s.invalid),
                Ok(out) if out.polylines.is_empty() => {
                    self.pending
                        .skip(element, WarningKind::Degenerate, |s| &mut s.invalid);
                }
                Ok(out) => self.edges(path, element, material, &out),
            }
        }
    }

    /// A marked circle: a light at its centre.
    fn light(&mut self, path: &usvg::Path, element: usize, power: f64, to_plan: Affine) {
        let b = path.data().bounds();
        let centre = kurbo::Point::new(
            f64::from(b.left() + b.right()) / 2.0,
            f64::from(b.top() + b.bottom()) / 2.0,
        );
        let at = to_plan * centre;
        self.pending.lights.push(MarkedLight {
            element: self.source.elements[element].name.clone(),
            at: DVec2::new(at.x, at.y),
            power,
        });
    }

    /// The edges of `path`, whose outline is `out`.
    fn edges(&mut self, path: &usvg::Path, element: usize, material: Material, out: &Outline) {
        if out.merged > 0 {
            self.pending
                .warn(element, WarningKind::Merged { pieces: out.merged });
        }
        // What is seen: a fill that paints an area (a `<line>` keeps SVG's default fill, which
        // paints nothing), else a stroke.
        let paints_area =
            path.fill().is_some() && out.polylines.iter().any(|p| !collinear(&p.points));
        let faces = material
            .faces
            .unwrap_or(if paints_area || path.stroke().is_none() {
                Faces::Out
            } else {
                Faces::Both
            });
        let pieces: Vec<(DVec2, DVec2)> = out.polylines.iter().flat_map(|p| p.pieces()).collect();
        if material.role == ElementRole::Blocker {
            let two_sided = !matches!(faces, Faces::Left | Faces::Right);
            for &(a, b) in &pieces {
                let (a, b) = if faces == Faces::Right {
                    (b, a)
                } else {
                    (a, b)
                };
                let edge = Edge::blocker(a, b).with_two_sided(two_sided);
                self.pending.push(edge, element, false);
            }
            return;
        }
        let surface =
            |a, b| Edge::surface(a, b, material.reflectance).with_emission(material.emission);
        match faces {
            Faces::Out | Faces::In => {
                let rule = path.fill().map_or(FillRule::NonZero, usvg::Fill::rule);
                self.fill(element, out, rule, faces == Faces::In, surface);
            }
            Faces::Left => {
                for &(a, b) in &pieces {
                    self.pending.push(surface(a, b), element, false);
                }
            }
            Faces::Right => {
                for &(a, b) in pieces.iter().rev() {
                    self.pending.push(surface(b, a), element, false);
                }
            }
            Faces::Both => {
                for &(a, b) in &pieces {
                    self.pending.push(surface(a, b), element, false);
                    self.pending.push(surface(b, a), element, false);
                }
            }
        }
    }

    /// The edges of the region `out` fills under `rule`, facing out of it (into it when
    /// `inward`).
    fn fill(
        &mut self,
        element: usize,
        out: &Outline,
        rule: FillRule,
        inward: bool,
        surface: impl Fn(DVec2, DVec2) -> Edge,
    ) {
        match fill_edges(&out.polylines, rule, inward) {
            Ok(fill) => {
                if fill.flat + fill.inside > 0 {
                    let kind = WarningKind::LoopsLeftOut {
                        flat: fill.flat,
                        inside: fill.inside,
                    };
                    self.pending.warn(element, kind);
                }
                for (a, b) in fill.edges {
                    self.pending.push(surface(a, b), element, !inward);
                }
            }
            Err(FillProblem::Crosses(at)) => {
                self.pending
                    .skip(element, WarningKind::Crosses { at }, |s| &mut s.invalid);
            }
            Err(FillProblem::NoArea) => {
                self.pending
                    .skip(element, WarningKind::Degenerate, |s| &mut s.invalid);
            }
        }
    }
}
