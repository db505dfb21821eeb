//! The CI pass of the fuzz targets: a fixed-seed run of every library reader (a few thousand
//! inputs each, seconds in all), and the allocation bound checked with a lying header for each
//! binary or counted format, under the counting allocator.

use fuzz::engine::alloc::{self, Counting};
use fuzz::{Limits, Report};
use std::path::PathBuf;

#[global_allocator]
static ALLOC: Counting = Counting;

/// Inputs per target in CI: enough to reach every mutation kind many times, a few seconds in
/// all on the dev profile.
const CI_INPUTS: u64 = 3000;

#[test]
fn every_reader_survives_a_fixed_seed_pass() {
    let mut failed = Vec::new();
    let mut names = Vec::new();
    for t in fuzz::targets::all() {
        let r: Report = fuzz::run(&t, 45, &Limits::ci(CI_INPUTS));
        println!("{}", r.summary());
        assert_eq!(r.inputs, CI_INPUTS);
        assert!(r.counted, "the counting allocator is not installed");
        // A pass where every input is refused (or accepted) reaches little of the reader.
        assert!(r.accepted > 0 && r.refused > 0, "{}", r.summary());
        if !r.clean() {
            failed.push(r.details(300));
        }
        names.push(t.name);
    }
    fuzz::targets::remove_scratch();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
    assert!(names.len() >= 15, "{names:?}");
}

#[test]
fn a_replay_counts_memory_and_judges_by_the_rules_of_a_run() {
    let targets = fuzz::targets::all();
    let t = targets.iter().find(|t| t.name == "tum-list").unwrap();
    let limits = Limits::long(1.0, std::env::temp_dir());
    let ok = fuzz::engine::driver::replay(t, b"1.0 rgb/1.png\n", &limits);
    assert!(
        ok.outcome.is_ok() && ok.broken.is_empty(),
        "{}",
        ok.summary()
    );
    assert!(ok.peak_bytes.is_some(), "not counted");
    let bad = fuzz::engine::driver::replay(t, b"1.0\n", &limits);
    let e = bad.outcome.as_ref().unwrap_err();
    assert!(
        e.contains("rgb.txt") && bad.broken.is_empty(),
        "{}",
        bad.summary()
    );
    fuzz::targets::remove_scratch();
}

/// Bytes live at once while `f` runs (beyond those live before).
fn peak_of<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let base = alloc::reset_peak();
    let out = f();
    (out, (alloc::peak() - base).max(0) as usize)
}

/// A scratch folder of one test, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(test: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("nf-fuzz-{test}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The reader refuses the lying file, naming `want`, holding less than `limit` bytes at once.
fn refused_small<E: std::fmt::Display>(
    what: &str,
    limit: usize,
    want: &str,
    read: impl FnOnce() -> Result<(), E>,
) {
    let (r, peak) = peak_of(read);
    let e = match r {
        Ok(()) => panic!("{what}: a lying header was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains(want), "{what}: {e}");
    assert!(peak < limit, "{what}: {peak} bytes live for a lying header");
}

#[test]
fn a_binary_vocabulary_claiming_4e9_nodes_is_refused_unallocated() {
    // The header of a real vocabulary with its node count set to u32::MAX (4.3e9 nodes, 190 GB
    // of records) and its checksum repaired: refused from the length, before any node is read.
    use slam_core::place::vocabulary::Vocabulary;
    let voc = fuzz::targets::all()
        .into_iter()
        .find(|t| t.name == "vocab-binary")
        .unwrap();
    let mut b = voc.mutator.seeds()[0].clone();
    b[18..22].copy_from_slice(&u32::MAX.to_le_bytes());
    fuzz::fixup::vocabulary_checksum(&mut b);
    refused_small("vocabulary", 64 << 10, "expected", || {
        Vocabulary::from_bytes(&b).map(|_| ())
    });
    // A depth of 1000 levels (kept in a byte per node) is refused as the text form refuses it.
    let mut deep = voc.mutator.seeds()[0].clone();
    deep[12..16].copy_from_slice(&1000u32.to_le_bytes());
    fuzz::fixup::vocabulary_checksum(&mut deep);
    refused_small("vocabulary depth", 64 << 10, "L = 1000", || {
        Vocabulary::from_bytes(&deep).map(|_| ())
    });
    // And 10^12 nodes in the text form's place: a header line alone holds no count, so a file
    // of a few lines is a few nodes, whatever it says.
    refused_small("text vocabulary", 64 << 10, "line", || {
        Vocabulary::from_bytes(b"1000000000000 6 0 0\n0 0 1\n").map(|_| ())
    });
}

#[test]
fn a_png_claiming_4g_pixels_is_refused_unallocated() {
    let png = fuzz::targets::all()
        .into_iter()
        .find(|t| t.name == "png-gray")
        .unwrap();
    let mut b = png.mutator.seeds()[0].clone();
    // IHDR's width and height (bytes 16..24) set to 65535 x 65535, CRC repaired.
    b[16..24].copy_from_slice(&[0, 0, 0xff, 0xff, 0, 0, 0xff, 0xff]);
    fuzz::fixup::png_crcs(&mut b);
    let dir = Scratch::new("png");
    let p = dir.write("liar.png", &b);
    refused_small("png gray", 1 << 20, "65535x65535", || {
        datasets::decode::read_gray(&p).map(|_| ())
    });
    refused_small("png depth", 1 << 20, "65535x65535", || {
        datasets::decode::read_depth(&p, 5000.0).map(|_| ())
    });
    refused_small("any image", 1 << 20, "65535x65535", || {
        datasets::decode::read_image(&p).map(|_| ())
    });
}

#[test]
fn settings_and_sensor_files_claiming_huge_images_or_matrices_are_refused_unallocated() {
    let dir = Scratch::new("settings");
    let settings = fuzz::targets::all()
        .into_iter()
        .find(|t| t.name == "settings-yaml")
        .unwrap();
    // The raw EuRoC rig (ORB-SLAM2 layout, LEFT.* / RIGHT.*): its size drives the
    // rectification maps, 8 bytes a pixel a camera.
    let rig = settings
        .mutator
        .seeds()
        .iter()
        .map(|s| String::from_utf8(s.clone()).unwrap())
        .find(|s| s.contains("LEFT.width: 75") && !s.contains("File.version"))
        .unwrap();
    for (from, to, want) in [
        (
            "LEFT.width: 75",
            "LEFT.width: 4000000000",
            "must be <= 8192",
        ),
        (
            "Camera.width: 75",
            "Camera.width: 4000000",
            "must be <= 8192",
        ),
        ("rows: 3", "rows: 4000000000", "4000000000x3"),
        ("rows: 3", "rows: 18446744073709551615", "LEFT.K"),
    ] {
        assert!(rig.contains(from), "{from}");
        let p = dir.write("liar.yaml", rig.replacen(from, to, 1).as_bytes());
        refused_small(to, 1 << 20, want, || {
            datasets::settings::read_settings(&p, slam_core::SensorKind::Stereo).map(|_| ())
        });
    }
    // ORB-SLAM3's raw pair is rectified while the file is read: its size is checked first
    // (found by fuzzing: this width asked for an 824 GB map).
    let o3 = settings
        .mutator
        .seeds()
        .iter()
        .map(|s| String::from_utf8(s.clone()).unwrap())
        .find(|s| s.contains("Stereo.T_c1_c2") && s.contains("Camera.width: 75"))
        .unwrap();
    let p = dir.write(
        "o3.yaml",
        o3.replace("Camera.width: 75", "Camera.width: 742949672955")
            .as_bytes(),
    );
    refused_small("orb-slam3 width", 1 << 20, "must be <= 8192", || {
        datasets::settings::read_settings(&p, slam_core::SensorKind::Stereo).map(|_| ())
    });
    let sensor = include_str!("../../seeds/euroc-cam0-sensor.yaml");
    let p = dir.write(
        "sensor.yaml",
        sensor
            .replace("[752, 480]", "[4000000000, 4000000000]")
            .as_bytes(),
    );
    refused_small("sensor.yaml", 1 << 20, "resolution", || {
        datasets::euroc::read_sensor_yaml(&p).map(|_| ())
    });
}

#[test]
fn a_text_file_of_a_million_character_line_is_refused_in_linear_memory() {
    // A TUM list whose stamp is a million digits: refused (it is no finite number) at a small
    // multiple of the file's size, not a copy per field.
    let dir = Scratch::new("long-line");
    let line = "1".repeat(1 << 20);
    let p = dir.write("rgb.txt", format!("{line} rgb/a.png\n").as_bytes());
    let (r, peak) = peak_of(|| datasets::tum::read_list(&p).map(|_| ()));
    let e = r.unwrap_err().to_string();
    assert!(e.contains("rgb.txt:1"), "{}", &e[..200.min(e.len())]);
    assert!(peak < 8 << 20, "{peak}");
}
