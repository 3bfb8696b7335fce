//! Messages to stderr that cannot fail a render.

/// `eprintln!` that ignores a failed write: a closed or full stderr (`illum render … 2>&1 | head
/// -1`) must not stop a render or fail one already written (`eprintln!` panics on it).
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}
