//! Log–log slopes of cost against edges: how a method's time and memory grow with the scene.

use flatland_geom::generate::SceneKind;

use super::Scaling;
use crate::timed::Method;

/// The least-squares slope of `ln cost` against `ln edges` of one method on one kind of scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slope {
    /// The kind of scene.
    pub kind: SceneKind,
    /// The method.
    pub method: Method,
    /// Of time to the lit scene (`None`: fewer than two sizes measured).
    pub time: Option<f64>,
    /// Of the peak memory added.
    pub memory: Option<f64>,
    /// Edges of the smallest and largest scene fitted.
    pub edges: (usize, usize),
}

/// The least-squares slope through `(x, y)` in log–log, from two points up; points with a
/// value that is not positive are left out.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let (mx, my) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Per kind and method with rows, the slopes over the scenes of at most `max_edges` edges.
pub fn slopes(all: &Scaling, max_edges: usize) -> Vec<Slope> {
    let mut out: Vec<Slope> = Vec::new();
    for r in all.rows.iter().filter(|r| !r.skipped && !r.row.failed) {
        let scene = &all.scenes[r.scene];
        if scene.edges > max_edges
            || out
                .iter()
                .any(|s| s.kind == scene.kind && s.method == r.row.method)
        {
            continue;
        }
        let mine: Vec<_> = all
            .rows
            .iter()
            .filter(|o| !o.skipped && !o.row.failed && o.row.method == r.row.method)
            .filter(|o| all.scenes[o.scene].kind == scene.kind)
            .filter(|o| all.scenes[o.scene].edges <= max_edges)
            .collect();
        let edges = |o: &&super::ScalingRow| all.scenes[o.scene].edges as f64;
        let time: Vec<(f64, f64)> = mine.iter().map(|o| (edges(o), o.row.total_s)).collect();
        let memory: Vec<(f64, f64)> = mine
            .iter()
            .filter_map(|o| o.peak.map(|p| (edges(o), p as f64)))
            .collect();
        let sizes = mine.iter().map(|o| all.scenes[o.scene].edges);
        out.push(Slope {
            kind: scene.kind,
            method: r.row.method,
            time: log_log_slope(&time),
            memory: log_log_slope(&memory),
            edges: (sizes.clone().min().unwrap_or(0), sizes.max().unwrap_or(0)),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn a_power_law_has_its_exponent_as_slope() {
        let points: Vec<(f64, f64)> = [100.0, 1000.0, 10_000.0]
            .iter()
            .map(|&x: &f64| (x, 3.0 * x.powf(1.25)))
            .collect();
        let s = log_log_slope(&points).unwrap();
        assert_close!(s, 1.25, 1e-12);
        assert_eq!(log_log_slope(&points[..1]), None);
        // A zero (nothing measured) is left out rather than taken as -∞.
        let with_zero = [(10.0, 0.0), (100.0, 1.0), (1000.0, 10.0)];
        assert_close!(log_log_slope(&with_zero).unwrap(), 1.0, 1e-12);
    }
}
