//! A solved radiosity as the CSV every command writes: one row per element, in order of `s`,
//! or one row per sample point of B as a function.

use crate::{FieldSample, Mesh};

/// The header of [`radiosity_csv`].
pub const RADIOSITY_HEADER: &str = "edge,s,x,y,b";

/// `edge,s,x,y,b`: one row per element midpoint of `mesh` in order of `s`, `b` its value
/// (shortest round-trip decimals, so the file reads back bit for bit).
#[must_use]
pub fn radiosity_csv(mesh: &Mesh, b: &[f64]) -> String {
    let mut out = format!("{RADIOSITY_HEADER}\n").into_bytes();
    radiosity_rows(&mut out, "", mesh, b).expect("writing to memory does not fail");
    String::from_utf8(out).expect("the rows are ASCII")
}

/// The rows of [`radiosity_csv`] without its header, each after `prefix` (`"3,"` for a
/// relighting's position column), written to `out` as they are made: a long relighting streams
/// them instead of holding every position's table.
pub fn radiosity_rows(
    out: &mut dyn std::io::Write,
    prefix: &str,
    mesh: &Mesh,
    b: &[f64],
) -> std::io::Result<()> {
    for (e, value) in mesh.elements().iter().zip(b) {
        let (x, y) = (e.midpoint.x, e.midpoint.y);
        writeln!(out, "{prefix}{},{},{x},{y},{value}", e.edge, e.s_mid)?;
    }
    Ok(())
}

/// B as a function at surface points ([`FinalGather::samples`](crate::FinalGather::samples))
/// as CSV: the header `edge,s,x,y,b`, one row per sample in the order given.
#[must_use]
pub fn samples_csv(samples: &[FieldSample]) -> String {
    let mut out = format!("{RADIOSITY_HEADER}\n");
    for p in samples {
        let (x, y) = (p.position.x, p.position.y);
        out.push_str(&format!("{},{},{x},{y},{}\n", p.edge, p.s, p.b));
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
        let mut prefixed = Vec::new();
        radiosity_rows(&mut prefixed, "7,", &mesh, &b).unwrap();
        let prefixed = String::from_utf8(prefixed).unwrap();
        for (row, plain) in prefixed.lines().zip(&rows[1..]) {
            assert_eq!(row, format!("7,{plain}"));
        }
        assert_eq!(prefixed.lines().count(), 64);
    }

    #[test]
    fn samples_are_rows_at_their_points() {
        let kernel = Kernel::new(bundled("fig3"));
        let mesh = Mesh::new(&kernel, 32).unwrap();
        let gather = crate::FinalGather::new(&kernel, &mesh).unwrap();
        let b = vec![0.5; 32];
        let samples = gather.samples(&b, 3, &crate::never).unwrap();
        let csv = samples_csv(&samples);
        let rows: Vec<&str> = csv.lines().collect();
        assert_eq!(rows[0], "edge,s,x,y,b");
        assert_eq!(rows.len(), 1 + 3 * 32);
        for (row, p) in rows[1..].iter().zip(&samples) {
            let cells: Vec<f64> = row.split(',').map(|c| c.parse().unwrap()).collect();
            assert_eq!(
                cells,
                [p.edge.index() as f64, p.s, p.position.x, p.position.y, p.b]
            );
        }
    }
}
