//! The ROS 2 bag importer on arbitrary bytes as a `.mcap` file, with the events fixture's
//! spec (grasps cut by an event topic, so the bag alone decides): MCAP records, chunk
//! decompression, schema checks, CDR decoding and the cutting into grasps.
#![no_main]

use std::path::Path;
use std::sync::{LazyLock, Once};

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::{ImportSpec, ros2};

#[path = "common.rs"]
mod common;

static SPEC: LazyLock<ImportSpec> = LazyLock::new(|| {
    let text = include_str!("../../tests/fixtures/ros2/zstd-events.spec.json");
    ImportSpec::from_str(text, Path::new("zstd-events.spec.json")).expect("the fixture spec reads")
});

/// libfuzzer-sys installs a panic hook that aborts at once, before `catch_unwind` can act,
/// so the bag reader's guard around the `mcap` crate (which panics on some damaged chunks)
/// would stop the fuzzer. The default hook is put back: a panic the reader catches is then
/// reported as a damaged bag, and any panic that escapes still aborts (libfuzzer-sys
/// catches it around the target and aborts).
static DEFAULT_PANIC_HOOK: Once = Once::new();

fuzz_target!(|data: &[u8]| {
    DEFAULT_PANIC_HOOK.call_once(|| drop(std::panic::take_hook()));
    // The bag reader takes files (a bag may be a folder of several), so the bytes go
    // through a scratch file, as a user's bag would.
    let path = common::scratch_file(data, "mcap");
    match ros2::import_bag(&path, &SPEC) {
        Ok(s) => assert!(!s.grasps.is_empty()),
        Err(e) => common::assert_names_file(&e, &path),
    }
});
