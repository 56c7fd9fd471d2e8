//! A solved radiosity as the CSV every command writes: one row per element, in order of `s`.

use crate::Mesh;

/// `edge,s,x,y,b`: one row per element midpoint of `mesh` in order of `s`, `b` its value
/// (shortest round-trip decimals, so the file reads back bit for bit).
#[must_use]
pub fn radiosity_csv(mesh: &Mesh, b: &[f64]) -> String {
    let mut out = String::from("edge,s,x,y,b\n");
    for (e, value) in mesh.elements().iter().zip(b) {
        let (x, y) = (e.midpoint.x, e.midpoint.y);
        out.push_str(&format!("{},{},{x},{y},{value}\n", e.edge, e.s_mid));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::bundled;
    use flatland_geom::Kernel;

    #[test]
    fn one_row_per_element_that_reads_back_exactly() {
        let kernel = Kernel::new(bundled("fig3"));
        let mesh = Mesh::new(&kernel, 64).unwrap();
        let b: Vec<f64> = (0..64).map(|i| 0.1 * f64::from(i) + 1.0 / 3.0).collect();
        let csv = radiosity_csv(&mesh, &b);
        let rows: Vec<&str> = csv.lines().collect();
        assert_eq!(rows[0], "edge,s,x,y,b");
        assert_eq!(rows.len(), 65);
        for (row, (e, &value)) in rows[1..].iter().zip(mesh.elements().iter().zip(&b)) {
            let cells: Vec<&str> = row.split(',').collect();
            assert_eq!(cells[0].parse::<usize>().unwrap(), e.edge.index());
            assert_eq!(cells[1].parse::<f64>().unwrap(), e.s_mid);
            assert_eq!(cells[4].parse::<f64>().unwrap(), value);
        }
    }
}
