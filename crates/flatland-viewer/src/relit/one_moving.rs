//! One light moving among many: B is linear in the lights, so while only light `k` moves, B is
//! the light of the others (solved once when `k` starts to move) plus light `k`'s alone. A
//! plan lit by hundreds of lamps then costs one light's view per move, not hundreds.

use flatland_geom::PointLight;

/// B of every light but the moving one, kept while only that one moves.
#[derive(Debug, Default)]
pub struct OneMoving {
    /// The lights of the last move.
    last: Vec<PointLight>,
    /// The moving light, and B of all the others (static light included).
    others: Option<(usize, Vec<f64>)>,
    /// The one light's B (static light included), then the sum.
    one: Vec<f64>,
    /// The static light alone (`None` until needed).
    still: Option<Vec<f64>>,
}

impl OneMoving {
    /// Forgets what was kept (another relighter answers from now on).
    pub fn forget(&mut self) {
        *self = OneMoving::default();
    }

    /// B under `lights` by `solve` (which writes B under the lights it is given, static light
    /// included, into its buffer): when only one light moved since the last call, by that
    /// light alone plus the others' B, kept.
    pub fn relight<E>(
        &mut self,
        lights: &[PointLight],
        mut solve: impl FnMut(&[PointLight], &mut Vec<f64>) -> Result<(), E>,
    ) -> Result<&[f64], E> {
        let moved = single_change(&self.last, lights);
        self.last = lights.to_vec();
        let Some(k) = moved.filter(|_| lights.len() > 1) else {
            self.others = None;
            solve(lights, &mut self.one)?;
            return Ok(&self.one);
        };
        if self.others.as_ref().is_none_or(|(m, _)| *m != k) {
            let rest: Vec<PointLight> = (0..lights.len())
                .filter(|&i| i != k)
                .map(|i| lights[i])
                .collect();
            let mut b = Vec::new();
            solve(&rest, &mut b)?;
            self.others = Some((k, b));
        }
        if self.still.is_none() {
            let mut still = Vec::new();
            solve(&[], &mut still)?;
            self.still = Some(still);
        }
        solve(&lights[k..=k], &mut self.one)?;
        if let (Some((_, others)), Some(still)) = (&self.others, &self.still) {
            for ((b, o), s) in self.one.iter_mut().zip(others).zip(still) {
                *b += o - s;
            }
        }
        Ok(&self.one)
    }
}

/// The one index at which `now` differs from `before` (of the same length), if exactly one.
fn single_change(before: &[PointLight], now: &[PointLight]) -> Option<usize> {
    if before.len() != now.len() {
        return None;
    }
    let mut changed = (0..now.len()).filter(|&i| before[i] != now[i]);
    let first = changed.next()?;
    changed.next().is_none().then_some(first)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::DVec2;

    /// A linear "solve": static light 1 everywhere, each light adding its position's
    /// coordinates times its power to three elements; counts the lights it was given.
    fn linear(count: &mut usize) -> impl FnMut(&[PointLight], &mut Vec<f64>) -> Result<(), ()> {
        move |lights, out| {
            *count += lights.len();
            out.clear();
            out.resize(3, 1.0);
            for l in lights {
                out[0] += l.power * l.at.x;
                out[1] += l.power * l.at.y;
                out[2] += l.power;
            }
            Ok(())
        }
    }

    #[test]
    fn one_moving_light_costs_one_light_and_gives_the_whole_b() {
        let mut lights: Vec<PointLight> = (0..50)
            .map(|i| PointLight::new(DVec2::new(f64::from(i), 2.0), 0.5))
            .collect();
        let mut moving = OneMoving::default();
        let mut count = 0;
        let mut whole = 0;
        let first = moving
            .relight(&lights, linear(&mut count))
            .unwrap()
            .to_vec();
        let mut exact = Vec::new();
        linear(&mut whole)(&lights, &mut exact).unwrap();
        assert_eq!(first, exact);
        for step in 1..=10 {
            lights[7].at = DVec2::new(0.5 * f64::from(step), 3.0);
            let before = count;
            let b = moving
                .relight(&lights, linear(&mut count))
                .unwrap()
                .to_vec();
            let mut exact = Vec::new();
            linear(&mut whole)(&lights, &mut exact).unwrap();
            for (x, y) in b.iter().zip(&exact) {
                assert!(
                    (x - y).abs() <= 1e-12 * y.abs().max(1.0),
                    "{b:?} vs {exact:?}"
                );
            }
            // After the first move of light 7 (the others' B and the static light once),
            // one light per move.
            if step > 1 {
                assert_eq!(count - before, 1, "step {step}");
            }
        }
        // Two lights at once: everything again.
        lights[1].power = 2.0;
        lights[2].power = 2.0;
        let before = count;
        moving.relight(&lights, linear(&mut count)).unwrap();
        assert_eq!(count - before, lights.len());
    }

    #[test]
    fn a_single_change_is_found_only_when_it_is_one() {
        let a = PointLight::new(DVec2::new(1.0, 1.0), 1.0);
        let b = PointLight::new(DVec2::new(2.0, 1.0), 1.0);
        assert_eq!(single_change(&[a, a], &[a, b]), Some(1));
        assert_eq!(single_change(&[a, a], &[b, b]), None);
        assert_eq!(single_change(&[a, a], &[a, a]), None);
        assert_eq!(single_change(&[a], &[a, b]), None);
    }
}
