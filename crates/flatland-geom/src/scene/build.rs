//! Building a [`Scene`]: every edge validated, the parent groups and the parameterization's tables.

use super::{Edge, Group, Role, Scene};
use crate::{EdgeId, GeomError, SurfaceRank};

impl Scene {
    /// Validates `edges` and builds the scene, without lights ([`Scene::with_lights`] adds
    /// them). Errors name the first offending edge and the rule.
    pub fn new(edges: Vec<Edge>) -> Result<Scene, GeomError> {
        let runs = vec![1; edges.len()];
        Scene::from_runs(edges, &runs)
    }

    /// Builds a scene whose edges are grouped in consecutive runs of `runs[i]` pieces.
    pub(super) fn from_runs(edges: Vec<Edge>, runs: &[usize]) -> Result<Scene, GeomError> {
        for (i, edge) in edges.iter().enumerate() {
            edge.validate(i)?;
        }
        if !edges.iter().any(|e| e.role == Role::Surface) {
            return Err(GeomError::NoSurface { edges: edges.len() });
        }
        debug_assert_eq!(runs.iter().sum::<usize>(), edges.len());
        let mut groups = Vec::with_capacity(runs.len());
        let mut group_of = Vec::with_capacity(edges.len());
        let mut surface_groups = Vec::new();
        let mut cum = vec![0.0];
        let mut first = 0;
        for &count in runs {
            let parent = Edge {
                a: edges[first].a,
                b: edges[first + count - 1].b,
                ..edges[first]
            };
            let rank = (parent.role == Role::Surface).then(|| {
                surface_groups.push(groups.len());
                cum.push(cum.last().copied().unwrap_or(0.0) + parent.length());
                SurfaceRank::new(surface_groups.len() - 1)
            });
            group_of.extend(std::iter::repeat_n(groups.len(), count));
            groups.push(Group {
                first,
                count,
                a: parent.a,
                b: parent.b,
                normal: parent.normal(),
                length: parent.length(),
                edge: parent,
                rank,
            });
            first += count;
        }
        let total_length = *cum.last().unwrap_or(&0.0);
        // L is finite: every length passed `validate`, where |b − a|² must not overflow, so
        // each is below 1.4e154 and no realistic edge count can sum past f64::MAX.
        let surface_edges = (0..edges.len())
            .filter(|&i| edges[i].role == Role::Surface)
            .map(EdgeId::new)
            .collect();
        let inv_length = surface_groups
            .iter()
            .map(|&g| 1.0 / groups[g].length)
            .collect();
        let n = surface_groups.len();
        let nb = (4 * n).max(64);
        let buckets = (0..nb)
            .map(|b| {
                let arc = b as f64 / nb as f64 * total_length;
                cum[1..n].partition_point(|&c| c <= arc).min(n - 1) as u32
            })
            .collect();
        Ok(Scene {
            edges,
            lights: Vec::new(),
            group_of,
            groups,
            surface_edges,
            surface_groups,
            cum,
            inv_length,
            buckets,
            total_length,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn a_scene_without_surfaces_is_rejected() {
        let err = Scene::new(vec![Edge::blocker(v(0.0, 0.0), v(1.0, 0.0))])
            .unwrap_err()
            .to_string();
        assert!(err.contains("no surface edge"), "{err}");
        assert!(
            Scene::new(vec![])
                .unwrap_err()
                .to_string()
                .contains("no surface edge")
        );
    }
}
