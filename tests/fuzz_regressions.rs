//! Inputs found by fuzzing (`fuzz/`, see its README) that crashed or misled a reader: each
//! must now give an error that names the file and the field, without panicking.

use std::path::Path;

use tactile_workbench::session::native;

/// A native session whose layout is `sensors[0].layout = <layout>`, with one frame of two
/// values.
fn session_with_layout(layout: &str) -> String {
    format!(
        r#"{{"format":"tactile-workbench-session","version":1,"session":{{"meta":{{"name":"t","source":"s"}},
"sensors":[{{"name":"a","layout":{layout},"unit":"kPa","transform":{{"kind":"identity"}}}}],
"encoders":[],"label_sets":[],
"grasps":[{{"object":"o","labels":[],"key_frame":0,"frames":[{{"t":0.0,"taxels":[[1.0,2.0]]}}]}}]}}}}"#
    )
}

fn load_error(text: &str) -> String {
    let path = Path::new("fuzzed.json");
    let result = std::panic::catch_unwind(|| native::from_str(text, path));
    match result.expect("the reader panicked") {
        Ok(_) => panic!("accepted"),
        Err(e) => {
            let e = e.to_string();
            assert!(
                e.contains("fuzzed.json"),
                "the error does not name the file: {e}"
            );
            e
        }
    }
}

#[test]
fn grid_whose_taxel_count_overflows_is_rejected() {
    // 2^63 + 1 rows × 2 columns wraps to 2 taxels: the two values matched it.
    let e = load_error(&session_with_layout(
        r#"{"kind":"grid","rows":9223372036854775809,"cols":2}"#,
    ));
    assert!(e.contains("sensors[0].layout"), "{e}");
    assert!(e.contains("too large"), "{e}");
}

#[test]
fn sparse_grid_whose_area_overflows_is_rejected() {
    let e = load_error(&session_with_layout(
        r#"{"kind":"sparse_grid","rows":18446744073709551615,"cols":3,"cells":[[0,0],[0,1]]}"#,
    ));
    assert!(e.contains("sensors[0].layout"), "{e}");
    assert!(e.contains("too large"), "{e}");
}

#[test]
fn sparse_grid_with_a_huge_area_is_rejected_before_anything_draws_it() {
    // 10^9 × 10^9 does not overflow, but an image of it could never be allocated.
    let e = load_error(&session_with_layout(
        r#"{"kind":"sparse_grid","rows":1000000000,"cols":1000000000,"cells":[[0,0],[0,1]]}"#,
    ));
    assert!(
        e.contains("sensors[0].layout") && e.contains("too large"),
        "{e}"
    );
}
