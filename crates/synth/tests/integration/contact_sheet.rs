//! Contact sheets of generated frames, as files. (The TUM and EuRoC folders are written, and
//! tested, in `datasets::write`.)

use std::fs;
use std::path::PathBuf;

use synth::{Generator, SynthConfig};

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("synth-test-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    d
}

/// A contact sheet is written whole in the format its extension names (PNG, or JPEG for
/// `.jpg`), with no temporary file left beside it; a sequence too short is refused.
#[test]
fn contact_sheets_are_png_or_jpeg_by_extension() {
    let mut config = SynthConfig::preset("kinect").unwrap();
    (config.camera.width, config.camera.height) = (160, 120);
    (config.camera.cx, config.camera.cy) = (80.0, 60.0);
    let gen = Generator::new(config, 2);
    let dir = temp_dir("contact");
    fs::create_dir_all(&dir).unwrap();
    for (name, magic) in [
        ("sheet.png", &[0x89u8, b'P', b'N', b'G'][..]),
        ("sheet.jpg", &[0xFF, 0xD8, 0xFF][..]),
    ] {
        let path = dir.join(name);
        synth::write_contact_sheet(&gen, 20, 2, &path).unwrap();
        let bytes = fs::read(&path).unwrap();
        assert!(bytes.starts_with(magic), "{name}");
        let img = image::load_from_memory(&bytes).unwrap();
        let expected = synth::contact_sheet(&gen, &[0, 1]);
        assert_eq!(
            (img.width(), img.height()),
            (expected.width(), expected.height())
        );
    }
    assert_eq!(
        fs::read_dir(&dir).unwrap().count(),
        2,
        "no temporary files left"
    );
    let _ = fs::remove_dir_all(&dir);
}
