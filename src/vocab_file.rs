//! Reading and writing vocabulary files: DBoW2's text form (ORB-SLAM2's `ORBvoc.txt`) or our
//! binary form, told apart by the binary form's magic, with errors naming the file and line.

use anyhow::{Context, Result};
use slam_core::hash::fnv1a;
use slam_core::place::vocabulary::BINARY_MAGIC;
use slam_core::place::Vocabulary;
use std::path::Path;

/// Reads a vocabulary file in either form.
pub fn read(path: &Path) -> Result<Vocabulary> {
    let bytes =
        std::fs::read(path).with_context(|| format!("reading vocabulary {}", path.display()))?;
    if bytes.starts_with(BINARY_MAGIC) {
        return Vocabulary::from_binary(&bytes)
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()));
    }
    let text = String::from_utf8(bytes).map_err(|_| {
        anyhow::anyhow!(
            "{}: neither a DBoW2 text vocabulary (not UTF-8 text) nor a noisefree binary one (no {:?} magic)",
            path.display(),
            String::from_utf8_lossy(BINARY_MAGIC)
        )
    })?;
    Vocabulary::from_text(&text).map_err(|e| {
        if e.line > 0 {
            anyhow::anyhow!("{}:{}: {}", path.display(), e.line, e.message)
        } else {
            anyhow::anyhow!("{}: {}", path.display(), e.message)
        }
    })
}

/// Whether `path` names the text form (`.txt`); anything else is written in binary.
pub fn is_text_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("txt"))
}

/// Writes a vocabulary atomically, as text for a `.txt` path, else in binary.
pub fn write(path: &Path, voc: &Vocabulary) -> Result<()> {
    let bytes = if is_text_path(path) {
        voc.to_text().into_bytes()
    } else {
        voc.to_binary()
    };
    atomic_file::write(path, &bytes)?;
    Ok(())
}

/// The vocabulary a run uses, and a name for it that changes with its content (recorded with
/// sweep folders, so runs with different vocabularies are never resumed as each other).
#[derive(Clone, Debug)]
pub struct VocabularyChoice {
    /// The vocabulary; `None` runs the brute-force stand-ins (`--vocabulary none`).
    pub vocabulary: Option<std::sync::Arc<Vocabulary>>,
    /// `none`, or the file name with an FNV-1a 64 of its bytes.
    pub identity: String,
}

/// The vocabulary named by `--vocabulary` (or the config file's `vocabulary`): a file, `none`
/// for no place recognition (brute-force candidate search and matching, as before vocabularies
/// existed), or, when absent, the built-in one.
pub fn choose(flag: Option<&Path>) -> Result<VocabularyChoice> {
    match flag {
        None => Ok(VocabularyChoice {
            vocabulary: Some(default_vocabulary()),
            identity: format!(
                "built-in {DEFAULT_NAME} (fnv {:016x})",
                fnv1a(DEFAULT_BYTES)
            ),
        }),
        Some(p) if p.as_os_str() == "none" => Ok(VocabularyChoice {
            vocabulary: None,
            identity: "none".into(),
        }),
        Some(p) => {
            let bytes =
                std::fs::read(p).with_context(|| format!("reading vocabulary {}", p.display()))?;
            let name = p.file_name().map_or_else(
                || p.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            Ok(VocabularyChoice {
                vocabulary: Some(std::sync::Arc::new(read(p)?)),
                identity: format!("{name} (fnv {:016x})", fnv1a(&bytes)),
            })
        }
    }
}

/// File name of the vocabulary shipped in `assets/vocabulary/` and compiled into the binary.
pub use results::systems::BUILT_IN_VOCABULARY as DEFAULT_NAME;

/// The bytes of the shipped vocabulary (k 10, L 5, trained on synthetic renderings and the
/// real EuRoC frames of ../shared/data; recipe in assets/vocabulary/README.md).
const DEFAULT_BYTES: &[u8] = include_bytes!("../assets/vocabulary/noisefree-k10L5.voc");

/// The shipped vocabulary, parsed once per process: the one used when no `--vocabulary` is
/// given, so the embedded default needs no download.
pub fn default_vocabulary() -> std::sync::Arc<Vocabulary> {
    static VOC: std::sync::OnceLock<std::sync::Arc<Vocabulary>> = std::sync::OnceLock::new();
    VOC.get_or_init(|| {
        std::sync::Arc::new(
            Vocabulary::from_binary(DEFAULT_BYTES).expect("the shipped vocabulary is valid"),
        )
    })
    .clone()
}

#[cfg(test)]
mod tests {
    use super::*;
    use slam_core::feature::{OrbConfig, OrbExtractor};
    use slam_core::place::score_l1;

    #[test]
    fn shipped_vocabulary_loads_and_recognises_places_of_an_unseen_sequence() {
        let voc = default_vocabulary();
        assert_eq!((voc.k(), voc.levels()), (10, 5));
        assert!(voc.word_count() > 90_000, "{}", voc.word_count());
        // kinect seed 0 (its textures) was not among the training renderings. The camera
        // turns on the spot, a full turn in 600 frames: frame 597 revisits frame 0's view,
        // frames 150 and 300 look at other walls.
        let mut config = synth::SynthConfig::preset("kinect").unwrap();
        config.trajectory = synth::Trajectory::Spin;
        let generator = synth::Generator::try_new(config, 0).unwrap();
        let mut ex = OrbExtractor::new(OrbConfig::default());
        let mut bow = |i: usize| {
            let (_, d) = ex.extract(&generator.frame(i).gray);
            voc.transform(&d, 4).0
        };
        let a = bow(0);
        let s = |b: &slam_core::place::BowVector| score_l1(&a, b);
        let (near, revisit) = (s(&bow(3)), s(&bow(597)));
        let (side, back) = (s(&bow(150)), s(&bow(300)));
        assert!((s(&a) - 1.0).abs() < 1e-9);
        let other = side.max(back);
        assert!(
            near > 2.0 * other && revisit > 2.0 * other,
            "near {near:.3}, revisit {revisit:.3}, side {side:.3}, back {back:.3}"
        );
    }

    #[test]
    fn text_and_binary_files_read_alike_and_junk_is_named() {
        let voc = default_vocabulary();
        let dir = std::env::temp_dir().join(format!("nf-vocfile-{}", std::process::id()));
        let (t, b) = (dir.join("v.txt"), dir.join("v.bin"));
        write(&t, &voc).unwrap();
        write(&b, &voc).unwrap();
        assert!(std::fs::read_to_string(&t)
            .unwrap()
            .starts_with("10 5 0 0\n"));
        assert_eq!(read(&t).unwrap(), *voc);
        assert_eq!(read(&b).unwrap(), *voc);
        let junk = dir.join("junk.txt");
        std::fs::write(&junk, "10 5 0 0\n0 0 1 2 3\n").unwrap();
        let e = read(&junk).unwrap_err().to_string();
        assert!(e.contains("junk.txt:2:"), "{e}");
        let _ = std::fs::remove_dir_all(dir);
    }
}
