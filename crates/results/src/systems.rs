//! The definition of an external SLAM system, `[systems.NAME]` in the config TOML: the command
//! line as a template with named placeholders, where its trajectory appears and in which format,
//! the settings file it reads, the sensors it handles, and a per-run timeout.
//!
//! ```toml
//! [systems.orbslam2]
//! label = "ORB-SLAM2 (real)"          # the column heading in the tables
//! settings = "orbslam2"               # settings file written for it: orbslam2, orbslam3, none
//! vocabulary = "/opt/ORB_SLAM2/Vocabulary/ORBvoc.txt"   # default: ours, as DBoW2 text
//! timeout_s = 1800
//!
//! [systems.orbslam2.rgbd]
//! command = ["/opt/ORB_SLAM2/Examples/RGB-D/rgbd_tum", "{vocabulary}", "{settings}",
//!            "{sequence}", "{associations}"]
//! trajectory = "CameraTrajectory.txt" # relative to the working directory
//! format = "tum"
//! [systems.orbslam2.rgbd.env]         # this sensor's environment, over the system's `env`
//! OMP_NUM_THREADS = "1"
//! ```
//!
//! Paths are anchored to the TOML's folder, so a definition works from any current directory:
//! the program, every argument that names a relative path (holds a `/`, no placeholder, does not
//! start with `-`), `vocabulary` and a relative `workdir`; `{config_dir}` (the TOML's folder,
//! absolute) may be written anywhere, `env` values included. The trajectory stays relative to
//! the working directory. The folder's `systems.toml` records the anchored definition and the
//! vocabulary each system was given (`[vocabularies]`).

use anyhow::{bail, Context, Result};
use datasets::settings::SettingsFormat;
use serde::{Deserialize, Serialize};
use slam_core::SensorKind;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Every placeholder a command template, working directory or trajectory path may hold.
pub const PLACEHOLDERS: [(&str, &str); 14] = [
    (
        "sequence",
        "the sequence folder (TUM: the folder of rgb.txt; EuRoC: the folder of mav0)",
    ),
    (
        "settings",
        "the camera settings file written for the system (see `settings`)",
    ),
    (
        "vocabulary",
        "the vocabulary file (`vocabulary`, else noisefree's as DBoW2 text)",
    ),
    (
        "associations",
        "TUM: the associations file (t_rgb rgb/... t_depth depth/...) of the run's frames",
    ),
    (
        "times",
        "EuRoC: the run's frame stamps, nanoseconds, one per line",
    ),
    ("times_s", "EuRoC: the same stamps in seconds"),
    ("cam0", "EuRoC: the left images folder (mav0/cam0/data)"),
    ("cam1", "EuRoC: the right images folder (mav0/cam1/data)"),
    (
        "run_dir",
        "the run's own folder (the default working directory)",
    ),
    ("seed", "the run's seed (most systems ignore it)"),
    ("frames", "the number of frames of the run"),
    ("noisefree", "this noisefree executable"),
    ("trajectory", "where the trajectory is expected (absolute)"),
    (
        "config_dir",
        "the folder of the config TOML (absolute; filled when the file is read)",
    ),
];

/// How a trajectory file is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TrajectoryFormat {
    /// TUM: `t tx ty tz qx qy qz qw`, seconds (ORB-SLAM2's SaveTrajectoryTUM).
    Tum,
    /// TUM's columns with the stamp in nanoseconds (ORB-SLAM3's SaveTrajectoryEuRoC).
    TumNs,
    /// EuRoC ground-truth CSV (`#timestamp [ns], p_x, ..., q_w, q_x, ...`).
    Euroc,
    /// KITTI: 12 numbers a line, one line per frame of the sequence, in order.
    Kitti,
}

/// The command of one sensor (`[systems.NAME.rgbd]` / `[systems.NAME.stereo]`); fields left
/// out take the system's.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorCommand {
    /// The command line, program first, each argument a string with placeholders.
    pub command: Vec<String>,
    /// Where the trajectory appears, relative to the working directory.
    pub trajectory: Option<String>,
    /// Its format.
    pub format: Option<TrajectoryFormat>,
    /// The settings file layout this program reads.
    pub settings: Option<String>,
    /// The working directory (placeholders allowed).
    pub workdir: Option<String>,
    /// Per-run timeout, seconds.
    pub timeout_s: Option<f64>,
    /// Environment variables for this sensor's runs, over (and besides) the system's `env`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub env: BTreeMap<String, String>,
}

/// An external system as the config file declares it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SystemDef {
    /// Column heading in the tables [default: the system's name].
    pub label: Option<String>,
    /// The settings file layout: `orbslam2`, `orbslam3` or `none` [default: orbslam2].
    pub settings: Option<String>,
    /// The vocabulary passed as `{vocabulary}` [default: noisefree's, converted to DBoW2 text].
    pub vocabulary: Option<PathBuf>,
    /// Per-run timeout, seconds [default: 3600].
    pub timeout_s: Option<f64>,
    /// The working directory [default: `{run_dir}`; ORB-SLAM2's examples write their
    /// trajectory into the current directory].
    pub workdir: Option<String>,
    /// Where the trajectory appears, relative to the working directory [default:
    /// CameraTrajectory.txt].
    pub trajectory: Option<String>,
    /// Its format [default: tum].
    pub format: Option<TrajectoryFormat>,
    /// Environment variables set for the program.
    #[serde(default)]
    pub env: BTreeMap<String, String>,
    /// The RGB-D command (TUM layout).
    pub rgbd: Option<SensorCommand>,
    /// The stereo command (EuRoC layout).
    pub stereo: Option<SensorCommand>,
}

/// A system's command for one sensor with every default applied.
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    /// The system's name.
    pub name: String,
    /// Its column heading.
    pub label: String,
    /// Program and arguments, placeholders not yet filled.
    pub command: Vec<String>,
    /// Working directory template.
    pub workdir: String,
    /// Trajectory path template, relative to the working directory.
    pub trajectory: String,
    /// Trajectory format.
    pub format: TrajectoryFormat,
    /// Settings layout, `None` for none.
    pub settings: Option<SettingsFormat>,
    /// Vocabulary, `None`: noisefree's as DBoW2 text.
    pub vocabulary: Option<PathBuf>,
    /// Timeout.
    pub timeout: Duration,
    /// Environment.
    pub env: BTreeMap<String, String>,
}

/// Default per-run timeout.
pub const DEFAULT_TIMEOUT_S: f64 = 3600.0;

/// Longest per-run timeout accepted, seconds (a year).
pub const MAX_TIMEOUT_S: f64 = 31_536_000.0;

impl SystemDef {
    /// The command for `sensor`, `None` when the system does not handle it.
    pub fn resolve(&self, name: &str, sensor: SensorKind) -> Result<Option<Resolved>> {
        let Some(cmd) = (match sensor {
            SensorKind::Rgbd => &self.rgbd,
            SensorKind::Stereo => &self.stereo,
        }) else {
            return Ok(None);
        };
        let settings_name = cmd
            .settings
            .clone()
            .or_else(|| self.settings.clone())
            .unwrap_or_else(|| "orbslam2".into());
        let settings = match settings_name.as_str() {
            "none" => None,
            s => Some(SettingsFormat::parse(s).with_context(|| {
                format!("system {name}: settings {s:?} is not orbslam2, orbslam3 or none")
            })?),
        };
        let timeout_s = cmd
            .timeout_s
            .or(self.timeout_s)
            .unwrap_or(DEFAULT_TIMEOUT_S);
        // At most a year: `Duration` holds no more than 1.8e19 s, and a mistyped 1e300 must be
        // refused here, not panic when the run starts.
        if !(timeout_s > 0.0 && timeout_s <= MAX_TIMEOUT_S) {
            bail!(
                "system {name}: timeout_s = {timeout_s}: must be > 0 and <= {MAX_TIMEOUT_S} \
                 (a year)"
            );
        }
        Ok(Some(Resolved {
            name: name.to_string(),
            label: self.label.clone().unwrap_or_else(|| name.to_string()),
            command: cmd.command.clone(),
            workdir: cmd
                .workdir
                .clone()
                .or_else(|| self.workdir.clone())
                .unwrap_or_else(|| "{run_dir}".into()),
            trajectory: cmd
                .trajectory
                .clone()
                .or_else(|| self.trajectory.clone())
                .unwrap_or_else(|| "CameraTrajectory.txt".into()),
            format: cmd.format.or(self.format).unwrap_or(TrajectoryFormat::Tum),
            settings,
            vocabulary: self.vocabulary.clone(),
            timeout: Duration::from_secs_f64(timeout_s),
            env: {
                let mut env = self.env.clone();
                env.extend(cmd.env.clone());
                env
            },
        }))
    }

    /// Checks the definition: at least one sensor, a non-empty command, known placeholders.
    pub fn validate(&self, name: &str) -> Result<()> {
        if self.rgbd.is_none() && self.stereo.is_none() {
            bail!("system {name}: no [systems.{name}.rgbd] or [systems.{name}.stereo] command");
        }
        for (sensor, cmd) in [("rgbd", &self.rgbd), ("stereo", &self.stereo)] {
            let Some(cmd) = cmd else { continue };
            if cmd.command.is_empty() || cmd.command[0].trim().is_empty() {
                bail!("system {name}.{sensor}: `command` is empty");
            }
            let mut texts: Vec<&String> = cmd.command.iter().collect();
            texts.extend(cmd.workdir.iter().chain(&self.workdir));
            texts.extend(cmd.trajectory.iter().chain(&self.trajectory));
            texts.extend(cmd.env.values().chain(self.env.values()));
            for t in texts {
                for p in placeholders_in(t) {
                    if !PLACEHOLDERS.iter().any(|(k, _)| *k == p) {
                        bail!(
                            "system {name}.{sensor}: unknown placeholder {{{p}}} in {t:?} (known: {})",
                            PLACEHOLDERS
                                .iter()
                                .map(|(k, _)| format!("{{{k}}}"))
                                .collect::<Vec<_>>()
                                .join(", ")
                        );
                    }
                }
            }
        }
        self.resolve(name, SensorKind::Rgbd)?;
        self.resolve(name, SensorKind::Stereo)?;
        Ok(())
    }
}

/// The names between braces in `text`.
pub fn placeholders_in(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find('{') {
        let after = &rest[i + 1..];
        match after.find('}') {
            Some(j) => {
                out.push(after[..j].to_string());
                rest = &after[j + 1..];
            }
            None => break,
        }
    }
    out
}

/// Fills the placeholders of `text` from `values`; an unknown or unavailable one is an error.
pub fn fill(text: &str, values: &BTreeMap<&str, String>) -> Result<String> {
    let mut out = String::new();
    let mut rest = text;
    while let Some(i) = rest.find('{') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        let Some(j) = after.find('}') else {
            out.push_str(&rest[i..]);
            return Ok(out);
        };
        let key = &after[..j];
        match values.get(key) {
            Some(v) => out.push_str(v),
            None => bail!("{{{key}}} has no value for this sequence (in {text:?})"),
        }
        rest = &after[j + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// The `[systems]` table of a config file: every definition, validated, with relative paths
/// (program, vocabulary) taken relative to the file's folder.
pub fn systems_in_file(path: &Path) -> Result<BTreeMap<String, SystemDef>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let value: toml::Value =
        toml::from_str(&text).with_context(|| format!("{}: not valid TOML", path.display()))?;
    let Some(table) = value.get("systems") else {
        return Ok(BTreeMap::new());
    };
    let defs: BTreeMap<String, SystemDef> = table.clone().try_into().with_context(|| {
        format!(
            "{}: [systems] is not a table of system definitions",
            path.display()
        )
    })?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let dir = std::fs::canonicalize(if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    })
    .unwrap_or_else(|_| dir.to_path_buf());
    let mut out = BTreeMap::new();
    for (name, mut def) in defs {
        def.fill_config_dir(&dir);
        if crate::columns::ConfigKind::parse(&name).is_ok() {
            bail!(
                "{}: system {name:?} has the name of one of noisefree's configurations",
                path.display()
            );
        }
        def.validate(&name)
            .with_context(|| format!("{}", path.display()))?;
        let anchor = |p: &mut String| {
            if is_relative_path(p) {
                *p = dir.join(p.as_str()).display().to_string();
            }
        };
        for cmd in [def.rgbd.as_mut(), def.stereo.as_mut()]
            .into_iter()
            .flatten()
        {
            cmd.command.iter_mut().for_each(anchor);
            cmd.workdir.iter_mut().for_each(anchor);
        }
        def.workdir.iter_mut().for_each(anchor);
        if let Some(v) = &def.vocabulary {
            if v.is_relative() {
                def.vocabulary = Some(dir.join(v));
            }
        }
        out.insert(name, def);
    }
    Ok(out)
}

/// Whether a definition's string names a path relative to the TOML's folder: it holds a `/`
/// (a bare word such as `rgbd` is an argument, not a file), no placeholder, and is not an
/// option (`--out=a/b`).
fn is_relative_path(s: &str) -> bool {
    s.contains('/') && !s.contains('{') && !s.starts_with('-') && Path::new(s).is_relative()
}

impl SystemDef {
    /// Replaces `{config_dir}` with `dir` in every string of the definition.
    fn fill_config_dir(&mut self, dir: &Path) {
        let d = dir.display().to_string();
        let f = |s: &mut String| *s = s.replace("{config_dir}", &d);
        for cmd in [self.rgbd.as_mut(), self.stereo.as_mut()]
            .into_iter()
            .flatten()
        {
            cmd.command.iter_mut().for_each(f);
            cmd.workdir.iter_mut().for_each(f);
            cmd.trajectory.iter_mut().for_each(f);
            cmd.env.values_mut().for_each(f);
        }
        self.workdir.iter_mut().for_each(f);
        self.trajectory.iter_mut().for_each(f);
        self.env.values_mut().for_each(f);
        if let Some(v) = &self.vocabulary {
            let text = v.display().to_string();
            if text.contains("{config_dir}") {
                self.vocabulary = Some(PathBuf::from(text.replace("{config_dir}", &d)));
            }
        }
    }
}

/// The vocabulary a system is given, in words: its file (with its size when readable), or
/// noisefree's built-in one converted to DBoW2 text. Recorded in the folder's systems.toml and
/// named in the tables' captions.
pub fn vocabulary_note(def: &SystemDef) -> String {
    match &def.vocabulary {
        Some(p) => match std::fs::metadata(p) {
            Ok(m) => format!("{} ({:.1} MB)", p.display(), m.len() as f64 / 1e6),
            Err(_) => p.display().to_string(),
        },
        None => format!(
            "noisefree's built-in vocabulary ({}) as DBoW2 text",
            BUILT_IN_VOCABULARY
        ),
    }
}

/// File name of the vocabulary shipped in `assets/vocabulary/` and compiled into the binary:
/// what a system without its own vocabulary is given, converted to DBoW2 text.
pub const BUILT_IN_VOCABULARY: &str = "noisefree-k10L5.voc";

/// The file of a sweep folder that records the definition of every external system its runs
/// used: the tables take their column headings from it, and a sweep with another definition
/// under the same name is refused (its runs would be averaged with the recorded ones).
pub const SYSTEMS_FILE: &str = "systems.toml";

/// The external systems recorded in sweep folder `dir` (none when it has no [`SYSTEMS_FILE`]).
pub fn systems_of(dir: &Path) -> Result<BTreeMap<String, SystemDef>> {
    let path = dir.join(SYSTEMS_FILE);
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            let v: toml::Value = toml::from_str(&text)
                .with_context(|| format!("{}: not valid TOML", path.display()))?;
            match v.get("systems") {
                None => Ok(BTreeMap::new()),
                Some(t) => t
                    .clone()
                    .try_into()
                    .with_context(|| format!("{}: not system definitions", path.display())),
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(BTreeMap::new()),
        Err(e) => Err(e).with_context(|| format!("reading {}", path.display())),
    }
}

/// Records `used` in `dir`'s [`SYSTEMS_FILE`]; a system with recorded runs (`has_runs`) whose
/// definition changed is an error.
pub fn pin_systems(
    dir: &Path,
    used: &BTreeMap<String, SystemDef>,
    has_runs: impl Fn(&str) -> bool,
) -> Result<()> {
    if used.is_empty() {
        return Ok(());
    }
    let mut all = systems_of(dir)?;
    for (name, def) in used {
        if let Some(old) = all.get(name) {
            if old != def && has_runs(name) {
                bail!(
                    "{} holds runs of system {name} made with another definition (see its {}): \
                     use another --out folder, or give this system another name",
                    dir.display(),
                    SYSTEMS_FILE
                );
            }
        }
        all.insert(name.clone(), def.clone());
    }
    #[derive(Serialize)]
    struct File<'a> {
        systems: &'a BTreeMap<String, SystemDef>,
        vocabularies: BTreeMap<&'a str, String>,
    }
    let vocabularies = all
        .iter()
        .map(|(n, d)| (n.as_str(), vocabulary_note(d)))
        .collect();
    let text = format!(
        "# the external systems whose runs this folder holds (a sweep with another definition \
         under one of these names is refused here), and the vocabulary each was given\n{}",
        toml::to_string(&File {
            systems: &all,
            vocabularies,
        })
        .context("writing the system definitions")?
    );
    atomic_file::write(&dir.join(SYSTEMS_FILE), text.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_fill_and_unknown_ones_are_refused() {
        let mut v = BTreeMap::new();
        v.insert("seed", "3".to_string());
        v.insert("run_dir", "/r".to_string());
        assert_eq!(fill("{run_dir}/x-{seed}.txt", &v).unwrap(), "/r/x-3.txt");
        assert_eq!(fill("plain", &v).unwrap(), "plain");
        assert!(fill("{times}", &v).is_err());
        let def = SystemDef {
            rgbd: Some(SensorCommand {
                command: vec!["prog".into(), "{sequnce}".into()],
                ..SensorCommand::default()
            }),
            ..SystemDef::default()
        };
        let e = format!("{:#}", def.validate("x").unwrap_err());
        assert!(e.contains("{sequnce}") && e.contains("{sequence}"), "{e}");
        assert!(SystemDef::default().validate("y").is_err());
    }

    #[test]
    fn the_shipped_definitions_are_valid() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../systems/orbslam.toml");
        let defs = systems_in_file(&p).unwrap();
        for name in ["orbslam2", "orbslam3", "noisefree-external"] {
            for sensor in [SensorKind::Rgbd, SensorKind::Stereo] {
                assert!(
                    defs[name].resolve(name, sensor).unwrap().is_some(),
                    "{name}"
                );
            }
        }
        let o3 = defs["orbslam3"]
            .resolve("orbslam3", SensorKind::Stereo)
            .unwrap()
            .unwrap();
        assert_eq!(o3.format, TrajectoryFormat::TumNs);
        assert_eq!(o3.settings, Some(SettingsFormat::Orbslam3));
        // Absolute program paths stay as written.
        assert_eq!(o3.command[0], "/opt/orbslam3/Examples/Stereo/stereo_euroc");
    }

    #[test]
    fn sensor_fields_override_the_system_s() {
        let text = r#"
            [systems.s]
            label = "S (real)"
            timeout_s = 10
            format = "tum-ns"
            [systems.s.stereo]
            command = ["bin/s", "{cam0}"]
            timeout_s = 5
            settings = "orbslam3"
        "#;
        let dir = std::env::temp_dir().join(format!("nf-systems-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("c.toml");
        std::fs::write(&p, text).unwrap();
        let defs = systems_in_file(&p).unwrap();
        let r = defs["s"].resolve("s", SensorKind::Stereo).unwrap().unwrap();
        assert_eq!(r.timeout, Duration::from_secs(5));
        assert_eq!(r.format, TrajectoryFormat::TumNs);
        assert_eq!(r.settings, Some(SettingsFormat::Orbslam3));
        assert_eq!(r.label, "S (real)");
        assert_eq!(r.command[0], dir.join("bin/s").display().to_string());
        assert!(defs["s"].resolve("s", SensorKind::Rgbd).unwrap().is_none());
        std::fs::write(&p, "[systems.orb]\n[systems.orb.rgbd]\ncommand = [\"x\"]\n").unwrap();
        assert!(
            systems_in_file(&p).is_err(),
            "a system may not shadow `orb`"
        );
        std::fs::write(
            &p,
            "[systems.t]\nlabl = \"x\"\n[systems.t.rgbd]\ncommand = [\"x\"]\n",
        )
        .unwrap();
        let e = format!("{:#}", systems_in_file(&p).unwrap_err());
        assert!(e.contains("labl"), "{e}");
    }

    /// Relative paths in arguments and `{config_dir}` resolve against the TOML's folder; bare
    /// words, options and placeholders stay as written; the sensor's `env` goes over the system's.
    #[test]
    fn relative_arguments_config_dir_and_sensor_env() {
        let dir = std::env::temp_dir().join(format!("nf-systems-rel-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let dir = std::fs::canonicalize(&dir).unwrap();
        let p = dir.join("c.toml");
        std::fs::write(
            &p,
            r#"
            [systems.s]
            vocabulary = "voc/v.txt"
            env = { A = "system", B = "{config_dir}/b", C = "{run_dir}" }
            [systems.s.rgbd]
            command = ["venv/bin/python", "tools/s.py", "rgbd", "--out=x/y", "{run_dir}/t", "{config_dir}/z"]
            env = { A = "sensor" }
            "#,
        )
        .unwrap();
        let defs = systems_in_file(&p).unwrap();
        let r = defs["s"].resolve("s", SensorKind::Rgbd).unwrap().unwrap();
        let d = dir.display().to_string();
        assert_eq!(
            r.command,
            [
                format!("{d}/venv/bin/python"),
                format!("{d}/tools/s.py"),
                "rgbd".into(),
                "--out=x/y".into(),
                "{run_dir}/t".into(),
                format!("{d}/z"),
            ]
        );
        assert_eq!(r.env["A"], "sensor");
        assert_eq!(r.env["B"], format!("{d}/b"));
        assert_eq!(
            r.env["C"], "{run_dir}",
            "run-time placeholders are filled per run"
        );
        assert_eq!(r.vocabulary, Some(dir.join("voc/v.txt")));
        assert!(vocabulary_note(&defs["s"]).contains("voc/v.txt"));
        assert!(vocabulary_note(&SystemDef::default()).contains("built-in"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
