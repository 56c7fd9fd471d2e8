//! Parameter schemas: for each numeric parameter of a configurable thing its name, symbol, valid
//! range and help, in one place. Validation, the command line's `--set NAME=VALUE`, the viewer's
//! controls, the stress suite's out-of-range cases and the parameter table of
//! docs/ALGORITHM.md are all derived from it, so a range is written once.

use std::fmt;

/// One end of a valid range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    /// The value itself is valid.
    Closed(f64),
    /// Values up to, not including, this one are valid.
    Open(f64),
    /// No finite end on this side (infinities and NaN are never valid).
    None,
}

/// A valid range: an interval, optionally of integers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// The lower end.
    pub lo: Bound,
    /// The upper end.
    pub hi: Bound,
    /// Whether only whole numbers are valid.
    pub integer: bool,
}

impl Range {
    /// Real numbers between `lo` and `hi`.
    pub const fn real(lo: Bound, hi: Bound) -> Range {
        Range {
            lo,
            hi,
            integer: false,
        }
    }

    /// Whole numbers from `lo` (inclusive) up to `hi` (inclusive), if any.
    pub const fn integer(lo: f64, hi: Option<f64>) -> Range {
        Range {
            lo: Bound::Closed(lo),
            hi: match hi {
                Some(hi) => Bound::Closed(hi),
                None => Bound::None,
            },
            integer: true,
        }
    }

    /// Whether `v` is valid.
    pub fn contains(&self, v: f64) -> bool {
        let above = match self.lo {
            Bound::Closed(lo) => v >= lo,
            Bound::Open(lo) => v > lo,
            Bound::None => v > f64::NEG_INFINITY,
        };
        let below = match self.hi {
            Bound::Closed(hi) => v <= hi,
            Bound::Open(hi) => v < hi,
            Bound::None => v < f64::INFINITY,
        };
        above && below && (!self.integer || v.fract() == 0.0)
    }

    /// Values just outside the range, one per finite end, plus NaN and the infinities where
    /// they are representable in the parameter's type (real ranges only): what a validation
    /// must refuse.
    pub fn outside(&self) -> Vec<f64> {
        let step = |x: f64| {
            if self.integer {
                1.0
            } else {
                1e-9 * x.abs().max(1.0)
            }
        };
        let mut out = Vec::new();
        match self.lo {
            Bound::Closed(lo) if !(self.integer && lo <= 0.0) => out.push(lo - step(lo)),
            Bound::Open(lo) => out.push(lo),
            _ => {}
        }
        match self.hi {
            Bound::Closed(hi) => out.push(hi + step(hi)),
            Bound::Open(hi) => out.push(hi),
            Bound::None => {}
        }
        if !self.integer {
            out.extend([f64::NAN, f64::INFINITY, f64::NEG_INFINITY]);
        }
        out.retain(|v| !self.contains(*v));
        out
    }
}

/// A number as a table shows it: whole numbers below 10⁷ as they are, powers of two above as
/// `2^k`, other large or tiny magnitudes in scientific notation (`1e7`, `1e-8`).
pub fn number(v: f64) -> String {
    let a = v.abs();
    if v.is_nan() || a.is_infinite() {
        return v.to_string();
    }
    if a >= 1e7 && v.fract() == 0.0 {
        let k = a.log2();
        if k.fract() == 0.0 && v > 0.0 {
            return format!("2^{k}");
        }
        return format!("{v:e}");
    }
    if a != 0.0 && a < 1e-3 {
        return format!("{v:e}");
    }
    v.to_string()
}

impl fmt::Display for Range {
    /// Interval notation: `(0, 2)`, `[0, 1)`, `[3, ∞)`; whole numbers say so.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lo = match self.lo {
            Bound::Closed(v) => format!("[{}", number(v)),
            Bound::Open(v) => format!("({}", number(v)),
            Bound::None => "(−∞".to_owned(),
        };
        let hi = match self.hi {
            Bound::Closed(v) => format!("{}]", number(v)),
            Bound::Open(v) => format!("{})", number(v)),
            Bound::None => "∞)".to_owned(),
        };
        write!(f, "{lo}, {hi}")?;
        if self.integer {
            write!(f, ", whole")?;
        }
        Ok(())
    }
}

/// One numeric parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spec {
    /// The field name, as files, `--set` and errors spell it.
    pub name: &'static str,
    /// The symbol of docs/ALGORITHM.md (`η`, `λ`, …).
    pub symbol: &'static str,
    /// The valid values.
    pub range: Range,
    /// One line of help.
    pub help: &'static str,
}

/// A configurable thing whose numeric parameters are described by a schema.
pub trait Schema {
    /// Every numeric parameter, in the order tables list them.
    fn specs() -> Vec<Spec>;

    /// The value of parameter `name` (whole numbers as `f64`), `None` for an unknown name.
    fn get(&self, name: &str) -> Option<f64>;

    /// Sets parameter `name` to `value` (not validated; whole-number fields take `value` as
    /// is, so call [`Schema::invalid`] first or validate after). `false` for an unknown name.
    fn set(&mut self, name: &str, value: f64) -> bool;

    /// The first parameter outside its range: `(spec, value)`.
    fn invalid(&self) -> Option<(Spec, f64)> {
        Self::specs().into_iter().find_map(|spec| {
            let value = self.get(spec.name)?;
            (!spec.range.contains(value)).then_some((spec, value))
        })
    }

    /// The spec of parameter `name`.
    fn spec(name: &str) -> Option<Spec> {
        Self::specs().into_iter().find(|s| s.name == name)
    }
}

/// Parses `NAME=VALUE` and sets it on `params` if `VALUE` is in the range of `NAME`; the error
/// names the parameter and its range, or lists the valid names.
pub fn set_checked<S: Schema>(params: &mut S, assignment: &str) -> Result<(), String> {
    let (name, value) = assignment
        .split_once('=')
        .ok_or_else(|| format!("`{assignment}`: expected NAME=VALUE"))?;
    let (name, value) = (name.trim(), value.trim());
    let Some(spec) = S::spec(name) else {
        let names: Vec<&str> = S::specs().iter().map(|s| s.name).collect();
        return Err(format!(
            "unknown parameter `{name}`; the parameters are {}",
            names.join(", ")
        ));
    };
    let parsed: f64 = value.parse().map_err(|_| {
        format!(
            "parameter `{name}` must be a number in {}, but is `{value}`",
            spec.range
        )
    })?;
    if !spec.range.contains(parsed) {
        return Err(format!(
            "parameter `{name}` must be in {}, but is {value}",
            spec.range
        ));
    }
    params.set(name, parsed);
    Ok(())
}

/// A Markdown table of `specs` with the default of each in `defaults` (one column per named
/// set of defaults).
pub fn markdown_table<S: Schema>(defaults: &[(&str, &S)]) -> String {
    let mut out = String::from("| parameter | symbol | valid | ");
    for (name, _) in defaults {
        out.push_str(&format!("{name} | "));
    }
    out.push_str("meaning |\n|---|---|---|");
    out.push_str(&"---:|".repeat(defaults.len()));
    out.push_str("---|\n");
    for spec in S::specs() {
        let symbol = match spec.symbol {
            "" => "–".to_owned(),
            s => s.replace('|', "\\|"),
        };
        out.push_str(&format!("| `{}` | {symbol} | {} | ", spec.name, spec.range));
        for (_, params) in defaults {
            let v = params.get(spec.name).unwrap_or(f64::NAN);
            out.push_str(&format!("{} | ", number(v)));
        }
        out.push_str(&format!("{} |\n", spec.help));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_contain_what_they_say_and_refuse_what_is_outside() {
        let eta = Range::real(Bound::Open(0.0), Bound::Open(2.0));
        assert_eq!(eta.to_string(), "(0, 2)");
        assert!(eta.contains(1e-300) && eta.contains(1.999) && !eta.contains(2.0));
        assert!(!eta.contains(f64::NAN) && !eta.contains(0.0));
        let cells = Range::integer(3.0, None);
        assert_eq!(cells.to_string(), "[3, ∞), whole");
        assert!(cells.contains(3.0) && !cells.contains(3.5) && !cells.contains(2.0));
        let free = Range::real(Bound::Closed(0.0), Bound::None);
        assert!(!free.contains(f64::INFINITY) && free.contains(1e300));
        for range in [eta, cells, free, Range::integer(0.0, Some(10.0))] {
            let outside = range.outside();
            assert!(!outside.is_empty(), "{range}");
            assert!(outside.iter().all(|v| !range.contains(*v)), "{range}");
        }
        assert_eq!(Range::integer(0.0, None).outside(), Vec::<f64>::new());
        assert_eq!(
            Range::integer(1.0, Some(1e7)).to_string(),
            "[1, 1e7], whole"
        );
        assert_eq!(number(1e-8), "1e-8");
        assert_eq!(number(u64::MAX as f64), "2^64");
        assert_eq!(number(0.05), "0.05");
        assert_eq!(number(300.0), "300");
    }
}
