//! Local solves of `x = (I − A)⁻¹ r` for a block of right-hand sides that live on a few
//! elements, by shooting (progressive radiosity, Southwell's method): an element whose
//! unshot light is above a threshold adds it to its solution and sends it on through A. Light
//! decays at every bounce and through every door, so a solve touches only the elements its
//! light reaches above the threshold — the rooms around its sources — never all N. A is K,
//! read by columns: what a lit element lights.
//!
//! Memory is proportional to what a solve touches: the workspace maps an element to its slot
//! through one array of N indices, reset after every solve.

use std::collections::VecDeque;

use crate::{Columns, TransportError};

/// A block of `width` vectors that are zero outside `elements`: row `r` of `values`
/// (`values[r * width..(r + 1) * width]`) belongs to element `elements[r]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Block {
    pub width: usize,
    pub elements: Vec<u32>,
    pub values: Vec<f64>,
}

impl Block {
    /// The identity's columns on `elements`: one unit vector per element.
    pub fn unit(elements: &[u32]) -> Block {
        let width = elements.len();
        let mut values = vec![0.0; width * width];
        for r in 0..width {
            values[r * width + r] = 1.0;
        }
        Block {
            width,
            elements: elements.to_vec(),
            values,
        }
    }

    /// Row `r`.
    pub fn row(&self, r: usize) -> &[f64] {
        &self.values[r * self.width..(r + 1) * self.width]
    }

    /// Rows in ascending element order.
    fn sorted(mut self) -> Block {
        let mut order: Vec<usize> = (0..self.elements.len()).collect();
        order.sort_unstable_by_key(|&r| self.elements[r]);
        let mut values = Vec::with_capacity(self.values.len());
        for &r in &order {
            values.extend_from_slice(self.row(r));
        }
        self.elements = order.iter().map(|&r| self.elements[r]).collect();
        self.values = values;
        self
    }
}

/// What one thread reuses from solve to solve.
#[derive(Debug)]
pub(crate) struct Workspace {
    /// Per element: its slot in this solve, or `u32::MAX`.
    slot: Vec<u32>,
    /// Per slot: the element.
    touched: Vec<u32>,
    width: usize,
    /// Per slot: unshot light (`width` numbers).
    unshot: Vec<f64>,
    /// Per slot: the solution so far.
    solution: Vec<f64>,
    queued: Vec<bool>,
    queue: VecDeque<u32>,
    /// Per column: the threshold below which its unshot light stays.
    thresholds: Vec<f64>,
}

/// Most pushes a solve may make per element it touches, before it is declared not converging:
/// light that loses a fifth at every bounce falls below 1e-6 of itself in 62 bounces.
const MAX_PUSHES_PER_ELEMENT: usize = 4096;

impl Workspace {
    /// A workspace for meshes of `n` elements.
    pub fn new(n: usize) -> Workspace {
        Workspace {
            slot: vec![u32::MAX; n],
            touched: Vec::new(),
            width: 0,
            unshot: Vec::new(),
            solution: Vec::new(),
            queued: Vec::new(),
            queue: VecDeque::new(),
            thresholds: Vec::new(),
        }
    }

    fn reset(&mut self, width: usize) {
        for &e in &self.touched {
            self.slot[e as usize] = u32::MAX;
        }
        self.touched.clear();
        self.unshot.clear();
        self.solution.clear();
        self.queued.clear();
        self.queue.clear();
        self.width = width;
    }

    /// The slot of element `e`, made on first use.
    fn slot_of(&mut self, e: u32) -> usize {
        let s = self.slot[e as usize];
        if s != u32::MAX {
            return s as usize;
        }
        let s = self.touched.len();
        self.slot[e as usize] = s as u32;
        self.touched.push(e);
        self.unshot.resize(self.unshot.len() + self.width, 0.0);
        self.solution.resize(self.solution.len() + self.width, 0.0);
        self.queued.push(false);
        s
    }

    /// `K b`, exactly: every row of `b` sent once.
    pub fn apply(&mut self, columns: &Columns, b: &Block) -> Block {
        self.reset(b.width);
        let width = b.width;
        for (r, &e) in b.elements.iter().enumerate() {
            let (to, fractions) = columns.column(e as usize);
            let light = b.row(r);
            for (&k, &f) in to.iter().zip(fractions) {
                let s = self.slot_of(k);
                let target = &mut self.unshot[s * width..(s + 1) * width];
                for (t, l) in target.iter_mut().zip(light) {
                    *t += f * l;
                }
            }
        }
        self.take(false)
    }

    /// `(I − K)⁻¹ r`, to `tolerance`: light is shot until no element holds
    /// unshot light above `tolerance` times the largest of its column in `r` (columns
    /// separately, so vectors of any scale are solved alike). Errors: light that keeps
    /// bouncing (a reflectance of 1 where light is trapped).
    pub fn solve(
        &mut self,
        columns: &Columns,
        r: &Block,
        tolerance: f64,
    ) -> Result<Block, TransportError> {
        self.reset(r.width);
        let width = r.width;
        self.thresholds = vec![0.0; width];
        for row in r.values.chunks_exact(width.max(1)) {
            for (t, v) in self.thresholds.iter_mut().zip(row) {
                *t = t.max(v.abs());
            }
        }
        self.thresholds.iter_mut().for_each(|t| *t *= tolerance);
        for (row, &e) in r.values.chunks_exact(width.max(1)).zip(&r.elements) {
            let s = self.slot_of(e);
            self.unshot[s * width..(s + 1) * width].copy_from_slice(row);
            self.enqueue_if_above(s);
        }
        let mut pushes = 0usize;
        let mut light = vec![0.0; width];
        while let Some(s) = self.queue.pop_front() {
            let s = s as usize;
            self.queued[s] = false;
            light.copy_from_slice(&self.unshot[s * width..(s + 1) * width]);
            self.unshot[s * width..(s + 1) * width].fill(0.0);
            for (x, l) in self.solution[s * width..(s + 1) * width]
                .iter_mut()
                .zip(&light)
            {
                *x += l;
            }
            let (to, fractions) = columns.column(self.touched[s] as usize);
            for (&k, &f) in to.iter().zip(fractions) {
                let t = self.slot_of(k);
                for (u, l) in self.unshot[t * width..(t + 1) * width]
                    .iter_mut()
                    .zip(&light)
                {
                    *u += f * l;
                }
                self.enqueue_if_above(t);
            }
            pushes += 1;
            if pushes > MAX_PUSHES_PER_ELEMENT * self.touched.len() {
                return Err(TransportError::NotConverged {
                    element: r.elements.first().map_or(0, |&e| e as usize),
                    pushes,
                });
            }
        }
        Ok(self.take(true))
    }

    fn enqueue_if_above(&mut self, s: usize) {
        if self.queued[s] {
            return;
        }
        let width = self.width;
        let above = self.unshot[s * width..(s + 1) * width]
            .iter()
            .zip(&self.thresholds)
            .any(|(u, t)| u.abs() > *t);
        if above {
            self.queued[s] = true;
            self.queue.push_back(s as u32);
        }
    }

    /// The solution (or, after [`Workspace::apply`], the unshot light) as a block, rows
    /// ascending.
    fn take(&mut self, solution: bool) -> Block {
        let values = if solution {
            std::mem::take(&mut self.solution)
        } else {
            std::mem::take(&mut self.unshot)
        };
        let block = Block {
            width: self.width,
            elements: self.touched.clone(),
            values,
        };
        self.reset(self.width);
        block.sorted()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::Kernel;
    use flatland_solve::{
        Mesh, SolveParams, TransferOperator, never, solve_linear, sweep_operator,
    };
    use flatland_testkit::assert_close;

    fn dense(block: &Block, n: usize, column: usize) -> Vec<f64> {
        let mut out = vec![0.0; n];
        for (r, &e) in block.elements.iter().enumerate() {
            out[e as usize] = block.row(r)[column];
        }
        out
    }

    #[test]
    fn a_local_solve_is_the_gmres_solve_within_its_tolerance() {
        let kernel = Kernel::new(flatland_geom::generate::floor_plan(300, 3).unwrap());
        let mesh = Mesh::new(&kernel, 2 * Mesh::min_elements(kernel.scene())).unwrap();
        let k = sweep_operator(&kernel, &mesh, &never).unwrap();
        let columns = Columns::of(&k);
        let n = mesh.len();
        let sources: Vec<u32> = vec![5, 6, 7, 400];
        let mut work = Workspace::new(n);
        let x = work.solve(&columns, &Block::unit(&sources), 1e-9).unwrap();
        for (c, &e) in sources.iter().enumerate() {
            let mut rhs = vec![0.0; n];
            rhs[e as usize] = 1.0;
            let exact = solve_linear(&k, &rhs, rhs.clone(), &SolveParams::default(), &never)
                .unwrap()
                .radiosity;
            let local = dense(&x, n, c);
            for i in 0..n {
                assert_close!(local[i], exact[i], 1e-7, "source {e}, element {i}");
            }
        }
    }

    #[test]
    fn a_local_solve_touches_only_the_rooms_its_light_reaches() {
        let kernel = Kernel::new(flatland_geom::generate::floor_plan(2000, 5).unwrap());
        let mesh = Mesh::new(&kernel, Mesh::min_elements(kernel.scene())).unwrap();
        let columns = Columns::of(&sweep_operator(&kernel, &mesh, &never).unwrap());
        let mut work = Workspace::new(mesh.len());
        let x = work.solve(&columns, &Block::unit(&[100]), 1e-3).unwrap();
        assert!(
            x.elements.len() < mesh.len() / 10,
            "{} of {} elements touched",
            x.elements.len(),
            mesh.len()
        );
        // And the workspace is clean for the next solve: the same answer again.
        assert_eq!(x, work.solve(&columns, &Block::unit(&[100]), 1e-3).unwrap());
    }

    #[test]
    fn apply_is_the_operator_product() {
        let kernel = Kernel::new(flatland_geom::bundled::scene("maze").unwrap());
        let mesh = Mesh::new(&kernel, 200).unwrap();
        let k = sweep_operator(&kernel, &mesh, &never).unwrap();
        let columns = Columns::of(&k);
        let mut work = Workspace::new(mesh.len());
        let b = Block::unit(&[3, 90]);
        let out = work.apply(&columns, &b);
        for c in 0..2 {
            let mut unit = vec![0.0; mesh.len()];
            unit[b.elements[c] as usize] = 1.0;
            let mut expected = vec![0.0; mesh.len()];
            k.apply(&unit, &mut expected);
            assert_eq!(dense(&out, mesh.len(), c), expected);
        }
    }
}
