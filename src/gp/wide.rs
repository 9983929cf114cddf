//! Runtime dispatch to code compiled for wider vector units.

/// Evaluates `$portable(args)` compiled for the first of the target features listed that
/// the CPU has (x86-64 only), else as it is. `$portable` must be `#[inline(always)]`, so
/// that each feature gets its own copy of it. Rust never reorders or fuses floating-point
/// operations, so every path gives bit-identical results. Expands to a function's tail:
/// the parameters are written `name: Type = value`, with concrete types (the wrappers are
/// nested functions, which cannot name `Self`).
macro_rules! dispatch_wide {
    ([$($feature:tt),+] $portable:path, $args:tt) => {
        dispatch_wide!([$($feature),+] $portable, $args -> ())
    };
    ([$($feature:tt),+] $portable:path, $args:tt -> $ret:ty) => {{
        #[cfg(target_arch = "x86_64")]
        {
            $(dispatch_wide!(@feature $feature, $portable, $args -> $ret);)+
        }
        dispatch_wide!(@call $portable, $args)
    }};
    (@feature $feature:tt, $portable:path, ($($arg:ident: $ty:ty = $val:expr),* $(,)?) -> $ret:ty) => {
        if std::arch::is_x86_feature_detected!($feature) {
            #[target_feature(enable = $feature)]
            unsafe fn wide($($arg: $ty),*) -> $ret {
                $portable($($arg),*)
            }
            // SAFETY: the CPU has the feature, checked just above.
            return unsafe { wide($($val),*) };
        }
    };
    (@call $portable:path, ($($arg:ident: $ty:ty = $val:expr),* $(,)?)) => {
        $portable($($val),*)
    };
}

pub(crate) use dispatch_wide;
