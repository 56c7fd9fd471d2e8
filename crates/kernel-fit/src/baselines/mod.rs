//! Baselines the SGCS fit is compared against (filled in by the benchmark issue).
