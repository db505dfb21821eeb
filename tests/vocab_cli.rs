//! End-to-end tests of `noisefree vocab`: train on rendered images, convert between the text
//! (DBoW2 / ORBvoc.txt) and binary forms, describe, and refuse bad files with file and line.

mod common;

use common::{assert_clean_failure, noisefree, noisefree_ok, tmpdir};

#[test]
fn train_convert_info_round_trip() {
    let dir = tmpdir("vocab");
    let seq = dir.join("seq");
    noisefree_ok(&[
        "synth",
        "--preset",
        "clean",
        "--frames",
        "8",
        "--seed",
        "3",
        "--out",
        seq.to_str().unwrap(),
    ]);
    let rgb = seq.join("rgb");
    let train = |out: &std::path::Path| {
        let o = noisefree_ok(&[
            "vocab",
            "train",
            "--images",
            rgb.to_str().unwrap(),
            "--k",
            "5",
            "--levels",
            "3",
            "--seed",
            "1",
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let bin = dir.join("v.voc");
    let s = train(&bin);
    assert!(s.contains("of 8 images"), "{s}");
    // Same seed, same bytes.
    let bin2 = dir.join("v2.voc");
    train(&bin2);
    assert_eq!(std::fs::read(&bin).unwrap(), std::fs::read(&bin2).unwrap());
    let txt = dir.join("v.txt");
    noisefree_ok(&[
        "vocab",
        "convert",
        bin.to_str().unwrap(),
        "-o",
        txt.to_str().unwrap(),
    ]);
    assert!(std::fs::read_to_string(&txt)
        .unwrap()
        .starts_with("5 3 0 0\n"));
    let back = dir.join("back.voc");
    noisefree_ok(&[
        "vocab",
        "convert",
        txt.to_str().unwrap(),
        "-o",
        back.to_str().unwrap(),
    ]);
    assert_eq!(std::fs::read(&bin).unwrap(), std::fs::read(&back).unwrap());
    let info = |p: &std::path::Path| {
        let o = noisefree_ok(&["vocab", "info", p.to_str().unwrap()]);
        let s = String::from_utf8_lossy(&o.stdout).into_owned();
        s.split(": ")
            .nth(1)
            .unwrap()
            .split(" (")
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(info(&bin), info(&txt));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_vocabulary_files_are_clean_errors() {
    let dir = tmpdir("vocab-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("ORBvoc.txt");
    std::fs::write(&p, "10 6 0 0\n0 0 1 2\n").unwrap();
    assert_clean_failure(
        &noisefree(&["vocab", "info", p.to_str().unwrap()]),
        "ORBvoc.txt:2:",
    );
    let p = dir.join("junk.bin");
    std::fs::write(&p, [0xffu8, 0xfe, 0x00, 0x01]).unwrap();
    assert_clean_failure(
        &noisefree(&["vocab", "info", p.to_str().unwrap()]),
        "junk.bin",
    );
    assert_clean_failure(
        &noisefree(&["vocab", "train", "--images", "/no/such/dir", "-o", "x.voc"]),
        "/no/such/dir",
    );
    let _ = std::fs::remove_dir_all(dir);
}
