//! [`assert_close!`](crate::assert_close): two numbers equal within an absolute or a relative
//! tolerance, or both; a failure names both expressions, their values and the difference.

/// Whether `a` and `b` agree: equal (infinities included), or both finite with `|a − b| ≤
/// max(abs, rel · max(|a|, |b|))`. NaN agrees with nothing, an infinity only with itself.
#[must_use]
pub fn is_close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    a == b
        || (a.is_finite() && b.is_finite() && (a - b).abs() <= abs.max(rel * a.abs().max(b.abs())))
}

/// The panic of a failed [`assert_close!`](crate::assert_close) (at the caller's line).
#[track_caller]
pub fn close_failed(
    a: f64,
    b: f64,
    rel: f64,
    abs: f64,
    what: [&str; 2],
    message: Option<String>,
) -> ! {
    let allowed = abs.max(rel * a.abs().max(b.abs()));
    let message = message.map_or_else(String::new, |m| format!(": {m}"));
    panic!(
        "assert_close!({a_what}, {b_what}) failed: {a_what} = {a:e}, {b_what} = {b:e}, \
         |difference| = {:e} > {allowed:e} (rel {rel:e}, abs {abs:e}){message}",
        (a - b).abs(),
        a_what = what[0],
        b_what = what[1],
    )
}

/// Asserts that two `f64` agree within a tolerance, naming both values when they do not:
///
/// ```
/// use flatland_testkit::assert_close;
/// assert_close!(0.1 + 0.2, 0.3, 1e-15); // absolute
/// assert_close!(1e9 + 1.0, 1e9, rel = 1e-8);
/// assert_close!(1e-20, 0.0, rel = 1e-9, abs = 1e-12); // either suffices
/// assert_close!(2.0_f64.sqrt().powi(2), 2.0, abs = 1e-15, "after {} steps", 1);
/// ```
///
/// `a` and `b` agree when equal (infinities included) or, both finite, when `|a − b| ≤
/// max(abs, rel · max(|a|, |b|))`; NaN never agrees. A bare third argument is an absolute
/// tolerance. Any further arguments are a `format!` message.
#[macro_export]
macro_rules! assert_close {
    (@check $a:expr, $b:expr, $rel:expr, $abs:expr $(, $($msg:tt)+)?) => {{
        let (a, b, rel, abs): (f64, f64, f64, f64) = ($a, $b, $rel, $abs);
        if !$crate::is_close(a, b, rel, abs) {
            let message: Option<String> = $crate::assert_close!(@message $($($msg)+)?);
            $crate::close_failed(a, b, rel, abs, [stringify!($a), stringify!($b)], message);
        }
    }};
    (@message) => {
        None
    };
    (@message $($msg:tt)+) => {
        Some(format!($($msg)+))
    };
    ($a:expr, $b:expr, rel = $rel:expr, abs = $abs:expr $(, $($msg:tt)+)?) => {
        $crate::assert_close!(@check $a, $b, $rel, $abs $(, $($msg)+)?)
    };
    ($a:expr, $b:expr, rel = $rel:expr $(, $($msg:tt)+)?) => {
        $crate::assert_close!(@check $a, $b, $rel, 0.0 $(, $($msg)+)?)
    };
    ($a:expr, $b:expr, abs = $abs:expr $(, $($msg:tt)+)?) => {
        $crate::assert_close!(@check $a, $b, 0.0, $abs $(, $($msg)+)?)
    };
    ($a:expr, $b:expr, $abs:expr $(, $($msg:tt)+)?) => {
        $crate::assert_close!(@check $a, $b, 0.0, $abs $(, $($msg)+)?)
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tolerances_absolute_relative_and_either() {
        assert!(is_close(1.0, 1.0 + 1e-10, 0.0, 1e-9));
        assert!(!is_close(1.0, 1.0 + 1e-8, 0.0, 1e-9));
        assert!(is_close(1e12, 1e12 + 1.0, 1e-11, 0.0));
        assert!(!is_close(1e12, 1e12 + 100.0, 1e-11, 0.0));
        // Near zero a relative tolerance alone accepts nothing but equality; abs rescues it.
        assert!(!is_close(1e-30, 0.0, 1e-9, 0.0));
        assert!(is_close(1e-30, 0.0, 1e-9, 1e-20));
        assert!(is_close(f64::INFINITY, f64::INFINITY, 0.0, 0.0));
        assert!(!is_close(f64::INFINITY, f64::NEG_INFINITY, 1.0, 1.0));
        assert!(!is_close(f64::INFINITY, 1e300, 1.0, 1.0));
        assert!(!is_close(f64::NAN, f64::NAN, 1.0, 1.0));
        assert!(!is_close(f64::NAN, 0.0, 1.0, f64::INFINITY));
    }

    #[test]
    fn the_macro_passes_within_tolerance() {
        let x = 0.1 + 0.2;
        crate::assert_close!(x, 0.3, 1e-15);
        crate::assert_close!(x, 0.3, abs = 1e-15);
        crate::assert_close!(x, 0.3, rel = 1e-15);
        crate::assert_close!(x, 0.3, rel = 0.0, abs = 1e-15, "x = {x}");
    }

    fn panic_text(f: impl FnOnce() + std::panic::UnwindSafe) -> String {
        let err = std::panic::catch_unwind(f).expect_err("the assertion should fail");
        err.downcast_ref::<String>().cloned().unwrap_or_default()
    }

    #[test]
    fn a_failure_names_both_values_the_difference_and_the_message() {
        let text = panic_text(|| {
            let measured = 1.5;
            crate::assert_close!(measured, 1.0, rel = 0.1, "case {}", 7);
        });
        assert!(text.contains("measured = 1.5e0"), "{text}");
        assert!(text.contains("1.0 = 1e0"), "{text}");
        assert!(text.contains("|difference| = 5e-1 > 1.5"), "{text}");
        assert!(text.ends_with(": case 7"), "{text}");
        let text = panic_text(|| crate::assert_close!(f64::NAN, 0.0, 1.0));
        assert!(text.contains("NaN"), "{text}");
    }
}
