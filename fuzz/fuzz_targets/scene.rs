//! Scene text (RON or JSON) → parse → validate → kernel evaluation must never panic.
//!
//! The first byte picks the format (even: RON, odd: JSON); the rest is the file's text. A
//! rejected file must give a one-line message with a position (parse errors) or naming the
//! edge (validation errors); an accepted scene must give finite, non-negative `k` and `ζ`.

#![no_main]

use flatland_geom::{GeomError, Kernel, Scene};
use libfuzzer_sys::fuzz_target;

/// Parameters probed on every accepted scene: interior points, ends, and out-of-range values
/// (which `Scene::point` wraps).
const PROBES: [f64; 9] = [0.0, 0.1, 0.25, 0.5, 0.7321, 0.999_999, -0.3, 1.5, f64::NAN];

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let result = if selector % 2 == 0 {
        Scene::from_ron_str(text)
    } else {
        Scene::from_json_str(text)
    };
    let scene = match result {
        Ok(scene) => scene,
        Err(err) => {
            let message = err.to_string();
            assert!(!message.contains('\n'), "multi-line error: {message:?}");
            if let GeomError::Parse { line, column, .. } = err {
                assert!(line >= 1 && column >= 1, "no position: {message:?}");
            }
            return;
        }
    };
    let total = scene.total_length();
    assert!(total.is_finite() && total > 0.0, "total length {total}");
    let kernel = Kernel::new(scene);
    for &s in &PROBES {
        let p = kernel.scene().point(s);
        assert!(
            p.position.is_finite() && p.normal.is_finite(),
            "point({s}) = {p:?}"
        );
        for &t in &PROBES {
            let k = kernel.k(s, t);
            let zeta = kernel.zeta(s, t);
            assert!(k.is_finite() && k >= 0.0, "k({s}, {t}) = {k}");
            assert!(zeta.is_finite() && zeta >= 0.0, "zeta({s}, {t}) = {zeta}");
        }
    }
});
