//! The ROS 2 bag importer on arbitrary bytes as a `.mcap` file, with the events fixture's
//! spec (grasps cut by an event topic, so the bag alone decides): MCAP records, chunk
//! decompression, schema checks, CDR decoding and the cutting into grasps.
#![no_main]

use std::path::Path;
use std::sync::LazyLock;

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::{ImportSpec, ros2};

#[path = "common.rs"]
mod common;

static SPEC: LazyLock<ImportSpec> = LazyLock::new(|| {
    let text = include_str!("../../tests/fixtures/ros2/zstd-events.spec.json");
    ImportSpec::from_str(text, Path::new("zstd-events.spec.json")).expect("the fixture spec reads")
});

fuzz_target!(|data: &[u8]| {
    // The bag reader takes files (a bag may be a folder of several), so the bytes go
    // through a scratch file, as a user's bag would.
    let path = common::scratch_file(data, "mcap");
    match ros2::import_bag(&path, &SPEC) {
        Ok(s) => assert!(!s.grasps.is_empty()),
        Err(e) => common::assert_names_file(&e, &path),
    }
});
