//! The light-driven learner's cells: probes, each the exact view of one receiver element's
//! midpoint, ordered along the sections of the receiving edges.
//!
//! A **section** is a run of elements of one surface edge between its ends and the junctions
//! where other edges touch it (a box standing on a floor cuts the floor into sections that see
//! different rooms), so a view is never borrowed across one. Every section starts with a probe
//! at each end; an element between two probes is *bracketed* by them and borrows both views
//! (the rows module blends them). A new probe goes to the middle of the pair of neighbours the
//! most uncertain light flows between, like a growing cell structure in one dimension: cells
//! on a chain, a new one inserted halfway along the edge with the largest resource.

use std::ops::Range;

use flatland_solve::{Mesh, SeenSpan};

/// One probe: the element whose midpoint was swept, and where its stretches lie in the arena.
#[derive(Clone, Debug)]
struct Probe {
    element: u32,
    spans: Range<u32>,
}

/// A cell of the light-driven learner: the receiver element whose view was probed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeCell {
    /// The receiver parameter of the probed point (the element's midpoint).
    pub t: f64,
    /// The element probed.
    pub element: usize,
}

/// How an element's row is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Bracket {
    /// It is probed: its row is exact.
    Probed(usize),
    /// It lies between probes `left` and `right` of its section, at fraction `f` of the way
    /// from the left one's midpoint to the right one's.
    Between { left: usize, right: usize, f: f64 },
}

/// Every section of a mesh with its probes, and the probes' views.
#[derive(Clone, Debug)]
pub(crate) struct Probes {
    /// Per section: its elements.
    sections: Vec<Range<u32>>,
    /// Per section: its probed elements, ascending.
    probed: Vec<Vec<u32>>,
    /// Per element: its section.
    section_of: Vec<u32>,
    /// Per element: its probe, if probed.
    probe_of: Vec<Option<u32>>,
    probes: Vec<Probe>,
    spans: Vec<SeenSpan>,
}

impl Probes {
    /// The sections of `mesh`, no probe yet.
    pub(crate) fn new(mesh: &Mesh) -> Probes {
        let mut sections: Vec<Range<u32>> = Vec::new();
        let mut section_of = vec![0; mesh.len()];
        for edge in mesh.edges() {
            let mut current: Option<usize> = None;
            for i in edge.elements.clone() {
                let u = (mesh.elements()[i].s_mid - edge.s[0]) / (edge.s[1] - edge.s[0]);
                let cut = edge.junctions.partition_point(|&j| j < u);
                if current != Some(cut) {
                    sections.push(i as u32..i as u32);
                    current = Some(cut);
                }
                let last = sections.len() - 1;
                sections[last].end = i as u32 + 1;
                section_of[i] = last as u32;
            }
        }
        Probes {
            probed: vec![Vec::new(); sections.len()],
            sections,
            section_of,
            probe_of: vec![None; mesh.len()],
            probes: Vec::new(),
            spans: Vec::new(),
        }
    }

    /// The elements the first round probes: both ends of every section.
    pub(crate) fn first(&self) -> Vec<usize> {
        let mut out = Vec::new();
        for range in &self.sections {
            let (a, b) = (range.start as usize, range.end as usize - 1);
            out.push(a);
            if b != a {
                out.push(b);
            }
        }
        out
    }

    /// Records the probe of `element` with the stretches it saw.
    pub(crate) fn add(&mut self, element: usize, spans: &[SeenSpan]) {
        debug_assert!(
            self.probe_of[element].is_none(),
            "element {element} probed twice"
        );
        let start = self.spans.len() as u32;
        self.spans.extend_from_slice(spans);
        let id = self.probes.len() as u32;
        self.probes.push(Probe {
            element: element as u32,
            spans: start..self.spans.len() as u32,
        });
        self.probe_of[element] = Some(id);
        let list = &mut self.probed[self.section_of[element] as usize];
        let at = list.partition_point(|&e| (e as usize) < element);
        list.insert(at, element as u32);
    }

    /// How element `i`'s row is made. Every element of a section with a probe at each end is
    /// probed or bracketed.
    pub(crate) fn bracket(&self, mesh: &Mesh, i: usize) -> Bracket {
        if let Some(p) = self.probe_of[i] {
            return Bracket::Probed(p as usize);
        }
        let list = &self.probed[self.section_of[i] as usize];
        let at = list.partition_point(|&e| (e as usize) < i);
        let (l, r) = (list[at - 1] as usize, list[at] as usize);
        let mid = |e: usize| mesh.elements()[e].s_mid;
        let f = (mid(i) - mid(l)) / (mid(r) - mid(l));
        Bracket::Between {
            left: self.probe_of[l].expect("a probed element") as usize,
            right: self.probe_of[r].expect("a probed element") as usize,
            f,
        }
    }

    /// The stretches probe `p` saw.
    pub(crate) fn spans(&self, p: usize) -> &[SeenSpan] {
        let range = &self.probes[p].spans;
        &self.spans[range.start as usize..range.end as usize]
    }

    /// Whether probe `p` sees stretch position `u` of mesh edge `edge`.
    pub(crate) fn sees(&self, p: usize, edge: u32, u: f64) -> bool {
        let spans = self.spans(p);
        let at = spans.partition_point(|s| (s.edge, s.u[1]) < (edge, u));
        spans
            .get(at)
            .is_some_and(|s| s.edge == edge && s.u[0] <= u && u <= s.u[1])
    }

    /// The element probe `p` probed.
    #[cfg(test)]
    pub(crate) fn element(&self, p: usize) -> usize {
        self.probes[p].element as usize
    }

    /// Number of probes.
    pub(crate) fn len(&self) -> usize {
        self.probes.len()
    }

    /// Whether every element is probed (the learned operator is then the exact one).
    pub(crate) fn complete(&self) -> bool {
        self.probes.len() == self.probe_of.len()
    }

    /// Every gap between neighbouring probes of a section with an element inside: the two
    /// probed elements, in section order.
    pub(crate) fn gaps(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.probed.iter().flat_map(|list| {
            list.windows(2)
                .filter(|w| w[1] > w[0] + 1)
                .map(|w| (w[0] as usize, w[1] as usize))
        })
    }

    /// Bytes held: the probes, their stretches and the per-element tables.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.probes.capacity() * std::mem::size_of::<Probe>()
            + self.spans.capacity() * std::mem::size_of::<SeenSpan>()
            + self
                .probed
                .iter()
                .map(|l| 4 * l.capacity() + 24)
                .sum::<usize>()
            + self.sections.capacity() * 8
            + self.section_of.capacity() * 4
            + self.probe_of.capacity() * 8
    }

    /// The cells, in the order probed.
    pub(crate) fn cells(&self, mesh: &Mesh) -> Vec<ProbeCell> {
        self.probes
            .iter()
            .map(|p| ProbeCell {
                t: mesh.elements()[p.element as usize].s_mid,
                element: p.element as usize,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::{Kernel, generate};

    fn mesh() -> Mesh {
        let kernel = Kernel::new(generate::floor_plan(120, 3).unwrap());
        Mesh::new(&kernel, 600).unwrap()
    }

    #[test]
    fn sections_cover_every_element_once_in_order() {
        let mesh = mesh();
        let probes = Probes::new(&mesh);
        let mut next = 0;
        for range in &probes.sections {
            assert_eq!(range.start as usize, next);
            assert!(range.end > range.start);
            let edge = mesh.elements()[next].mesh_edge;
            assert!(
                range
                    .clone()
                    .all(|i| mesh.elements()[i as usize].mesh_edge == edge)
            );
            next = range.end as usize;
        }
        assert_eq!(next, mesh.len());
    }

    #[test]
    fn after_the_first_probes_every_element_is_bracketed_between_its_neighbours() {
        let mesh = mesh();
        let mut probes = Probes::new(&mesh);
        for e in probes.first() {
            probes.add(e, &[]);
        }
        let mut between = 0;
        for i in 0..mesh.len() {
            match probes.bracket(&mesh, i) {
                Bracket::Probed(p) => assert_eq!(probes.element(p), i),
                Bracket::Between { left, right, f } => {
                    between += 1;
                    assert!(probes.element(left) < i && i < probes.element(right));
                    assert!(0.0 < f && f < 1.0, "{f}");
                }
            }
        }
        assert!(between > 0);
        let gaps: usize = probes.gaps().map(|(l, r)| r - l - 1).sum();
        assert_eq!(gaps, between);
    }

    #[test]
    fn a_probe_in_a_gap_splits_it() {
        let mesh = mesh();
        let mut probes = Probes::new(&mesh);
        for e in probes.first() {
            probes.add(e, &[]);
        }
        let (l, r) = probes.gaps().max_by_key(|&(l, r)| r - l).unwrap();
        let m = (l + r) / 2;
        probes.add(m, &[]);
        assert!(probes.gaps().any(|g| g.0 == l && g.1 == m) || m == l + 1);
        match probes.bracket(&mesh, m) {
            Bracket::Probed(p) => assert_eq!(probes.element(p), m),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn sees_finds_a_position_inside_a_stretch_only() {
        let mesh = mesh();
        let mut probes = Probes::new(&mesh);
        let spans = [
            SeenSpan {
                edge: 1,
                u: [0.2, 0.4],
            },
            SeenSpan {
                edge: 1,
                u: [0.6, 0.7],
            },
            SeenSpan {
                edge: 3,
                u: [0.0, 1.0],
            },
        ];
        probes.add(0, &spans);
        assert!(probes.sees(0, 1, 0.3));
        assert!(!probes.sees(0, 1, 0.5));
        assert!(probes.sees(0, 1, 0.65));
        assert!(!probes.sees(0, 2, 0.5));
        assert!(probes.sees(0, 3, 0.99));
        assert!(!probes.sees(0, 0, 0.3));
    }
}
