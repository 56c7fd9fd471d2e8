//! The self-check: simplicial topology, finite values, cached geometry, the spatial index.

use std::collections::BTreeMap;

use super::{CellId, Network};

/// How many triangles hold each edge `(a, b)`, `a < b`.
type EdgeTriangles = BTreeMap<(CellId, CellId), u32>;

impl Network {
    /// Checks the simplicial topology (every edge in one or two triangles, every triangle's edges
    /// present, no duplicates, symmetric sorted neighbour lists, Euler characteristic of a disk),
    /// finiteness of every value, cached widths and the spatial index.
    pub fn check_invariants(&self) -> Result<(), String> {
        self.cells.check_lengths(self.n, self.m)?;
        self.check_neighbour_lists()?;
        let edge_tris = self.check_triangles()?;
        self.check_edges(&edge_tris)?;
        self.check_finite_values()?;
        self.check_cached_geometry()?;
        self.index.check(&self.cells.pos, &self.cells.width)
    }

    /// Every cell has neighbours, strictly ascending, valid and symmetric.
    fn check_neighbour_lists(&self) -> Result<(), String> {
        let len = self.len();
        for (a, nb) in self.cells.nbrs.iter().enumerate() {
            if nb.is_empty() {
                return Err(format!("cell {a} has no neighbour"));
            }
            if nb.windows(2).any(|w| w[0] >= w[1]) {
                return Err(format!("neighbours of {a} not strictly ascending: {nb:?}"));
            }
            for &b in nb {
                if b == a || b >= len {
                    return Err(format!("cell {a} has invalid neighbour {b}"));
                }
                if self.cells.nbrs[b].binary_search(&a).is_err() {
                    return Err(format!("edge {a}-{b} is not symmetric"));
                }
            }
        }
        Ok(())
    }

    /// The triangles are distinct, sorted, made of edges, and listed by their corners (and
    /// only by them); returns how many triangles hold each edge.
    fn check_triangles(&self) -> Result<EdgeTriangles, String> {
        let len = self.len();
        let mut edge_tris = EdgeTriangles::new();
        let mut seen = self.tris.clone();
        seen.sort_unstable();
        if seen.windows(2).any(|w| w[0] == w[1]) {
            return Err("duplicate triangle".into());
        }
        for (t, tri) in self.tris.iter().enumerate() {
            if !(tri[0] < tri[1] && tri[1] < tri[2] && tri[2] < len) {
                return Err(format!("triangle {t} is malformed: {tri:?}"));
            }
            for (a, b) in [(0, 1), (0, 2), (1, 2)] {
                let (a, b) = (tri[a], tri[b]);
                if self.cells.nbrs[a].binary_search(&b).is_err() {
                    return Err(format!("triangle {t} {tri:?} lacks edge {a}-{b}"));
                }
                *edge_tris.entry((a, b)).or_default() += 1;
            }
            for &c in tri {
                if !self.cells.cell_tris[c].contains(&t) {
                    return Err(format!("cell {c} does not list its triangle {t}"));
                }
            }
        }
        for (c, ts) in self.cells.cell_tris.iter().enumerate() {
            if ts
                .iter()
                .any(|&t| t >= self.tris.len() || !self.tris[t].contains(&c))
            {
                return Err(format!("cell {c} lists a triangle it is not in"));
            }
        }
        Ok(edge_tris)
    }

    /// Every edge lies in one or two triangles, and the complex is a disk (`χ = 1`).
    fn check_edges(&self, edge_tris: &EdgeTriangles) -> Result<(), String> {
        let edges = self.edges();
        for e in &edges {
            match edge_tris.get(e) {
                Some(1 | 2) => {}
                other => {
                    return Err(format!(
                        "edge {e:?} is in {} triangles",
                        other.unwrap_or(&0)
                    ));
                }
            }
        }
        let euler = self.len() as i64 - edges.len() as i64 + self.tris.len() as i64;
        if euler != 1 {
            return Err(format!("Euler characteristic {euler}, a disk has 1"));
        }
        Ok(())
    }

    /// Positions, weights, counters and worst samples are finite, counters not negative.
    fn check_finite_values(&self) -> Result<(), String> {
        let cells = &self.cells;
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !finite(&cells.pos)
            || !finite(&cells.out)
            || !finite(&cells.err_mean)
            || !finite(&cells.cnt)
            || !finite(&cells.worst_err)
            || !finite(&cells.worst_in)
            || !finite(&cells.worst_out)
        {
            return Err("a position, output weight, counter or worst sample is not finite".into());
        }
        if cells
            .err_mean
            .iter()
            .chain(cells.cnt.iter())
            .chain(cells.worst_err.iter())
            .any(|&x| x < 0.0)
        {
            return Err("a counter is negative".into());
        }
        Ok(())
    }

    /// The cached edge lengths and widths equal fresh ones.
    fn check_cached_geometry(&self) -> Result<(), String> {
        for c in 0..self.len() {
            if self.cells.edge_len[c] != self.cells.measure_edges(c, self.n) {
                return Err(format!("cached edge lengths of {c} are stale"));
            }
            let w = self.cells.compute_width(c);
            if w != self.cells.width[c] {
                return Err(format!(
                    "cached width of {c} is {}, actual {w}",
                    self.cells.width[c]
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::test_support::{bump_ridge, grown};
    use crate::{Network, Params};

    fn small() -> Network {
        let p = Params {
            lambda: 20,
            ..Params::default()
        };
        grown(p, 1_000, 3, bump_ridge)
    }

    /// Each kind of damage is caught and named.
    #[test]
    fn damage_is_reported() {
        let net = small();
        net.check_invariants().unwrap();
        let expect = |damage: &dyn Fn(&mut Network), what: &str| {
            let mut broken = net.clone();
            damage(&mut broken);
            let err = broken.check_invariants().unwrap_err();
            assert!(err.contains(what), "{what:?} not in {err:?}");
        };
        expect(&|n| n.cells.width[4] *= 2.0, "cached width of 4");
        expect(
            &|n| n.cells.edge_len[5][0] += 1.0,
            "edge lengths of 5 are stale",
        );
        expect(&|n| n.cells.cnt[0] = -1.0, "negative");
        expect(&|n| n.cells.out[2] = f64::NAN, "not finite");
        expect(&|n| n.tris[0].swap(0, 1), "malformed");
        expect(&|n| n.tris.push(n.tris[0]), "duplicate triangle");
        expect(
            &|n| {
                let b = n.cells.nbrs[0][0];
                n.cells.nbrs[b].retain(|&c| c != 0);
            },
            "not symmetric",
        );
    }
}
