//! Building a run's `slam_core::system::Config`: the defaults for the sensor (ORB-SLAM2's TUM
//! or EuRoC settings), overlaid with a TOML file where every field is optional, then the
//! command line's switches (`--mcor`, `--avc`, `--mapping-lag`, `--seed`).

use anyhow::{Context, Result};
use slam_core::system::{AvcParams, ClusterViews, Config, McorParams, RigidConsensusParams};
use slam_core::techniques::params::AvcAim;
use slam_core::SensorKind;
use std::path::{Path, PathBuf};

/// The default configuration for a sensor: ORB-SLAM2's TUM RGB-D or EuRoC stereo settings.
pub fn base_config(sensor: SensorKind) -> Config {
    match sensor {
        SensorKind::Rgbd => Config::default(),
        SensorKind::Stereo => Config::stereo(),
    }
}

fn merge(base: &mut toml::Value, over: toml::Value) {
    match (base, over) {
        (toml::Value::Table(b), toml::Value::Table(o)) => {
            for (k, v) in o {
                match b.get_mut(&k) {
                    Some(slot) => merge(slot, v),
                    None => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (slot, v) => *slot = v,
    }
}

fn read_toml(path: &Path) -> Result<toml::Value> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    toml::from_str(&text).with_context(|| format!("{}: not valid TOML", path.display()))
}

/// The `vocabulary = "FILE"` of a configuration file (relative to the file's folder; `"none"`
/// for no place recognition), if it has one. It is the CLI's setting, not slam-core's: the
/// vocabulary is data handed to the system, not a parameter.
pub fn vocabulary_in_file(path: &Path) -> Result<Option<std::path::PathBuf>> {
    match read_toml(path)?.get("vocabulary") {
        None => Ok(None),
        Some(toml::Value::String(v)) if v == "none" => Ok(Some(v.into())),
        Some(toml::Value::String(v)) => Ok(Some(path.parent().unwrap_or(Path::new("")).join(v))),
        Some(_) => anyhow::bail!(
            "{}: `vocabulary` must be a file name (or \"none\")",
            path.display()
        ),
    }
}

/// The vocabulary a run is asked to use: the `--vocabulary` flag, else the `vocabulary` of the
/// `--config` file; `None`: the built-in one.
pub fn vocabulary_asked(flag: Option<&Path>, config: Option<&Path>) -> Result<Option<PathBuf>> {
    Ok(match (flag, config) {
        (Some(v), _) => Some(v.to_path_buf()),
        (None, Some(c)) => vocabulary_in_file(c)?,
        (None, None) => None,
    })
}

/// Overlays the TOML file at `path` (any subset of the fields of `Config`, plus `vocabulary`,
/// see [`vocabulary_in_file`]) on `base`.
pub fn overlay_file(base: &Config, path: &Path) -> Result<Config> {
    let mut over = read_toml(path)?;
    if let toml::Value::Table(t) = &mut over {
        t.remove("vocabulary");
        // External systems' definitions (`crate::external::system`), not the SLAM's settings.
        t.remove("systems");
    }
    let mut value = toml::Value::try_from(base).context("serialising the default configuration")?;
    merge(&mut value, over.clone());
    let config: Config = value
        .try_into()
        .with_context(|| format!("{}: not a valid noisefree configuration", path.display()))?;
    // serde ignores fields it does not know: a misspelt key would silently keep the default.
    // Every key of the file must survive a round trip through the configuration.
    let known = toml::Value::try_from(&config).context("serialising the configuration")?;
    let mut unknown = Vec::new();
    unknown_keys(&over, &known, "", &mut unknown);
    if !unknown.is_empty() {
        anyhow::bail!(
            "{}: unknown setting{} {} (`noisefree config` prints every setting with its \
             default)",
            path.display(),
            if unknown.len() == 1 { "" } else { "s" },
            unknown.join(", ")
        );
    }
    // Values that parse but make no sense (`[orb] scale_factor = 0.5`) are refused here, with
    // their range, before anything runs.
    config
        .check()
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(config)
}

/// Every setting of the config TOML with its default for `sensor`, the techniques' sections
/// included (present: switched on), as a file to start from.
pub fn defaults_text(sensor: SensorKind) -> Result<String> {
    let mut c = base_config(sensor);
    c.mcor = Some(McorParams::default());
    c.avc = Some(AvcParams::default());
    c.rc = Some(RigidConsensusParams::default());
    let body = toml::to_string(&c).context("serialising the defaults")?;
    Ok(format!(
        "# Every setting of noisefree's config TOML (`--config FILE`) with its default for a {} \
         sensor.\n# A file may hold any subset; a key not listed here is refused. The [mcor], \
         [avc] and [rc] sections switch\n# their technique on by being there (delete a section \
         to leave it off). Not listed because unset by\n# default: `rgbd_baseline = B` (the \
         RGB-D camera's baseline in metres; see docs/readings.md), and\n# `vocabulary = \
         \"FILE\"` (or \"none\") beside the settings.\n\n{body}",
        match sensor {
            SensorKind::Stereo => "stereo",
            SensorKind::Rgbd => "RGB-D",
        }
    ))
}

/// Dotted paths of the keys of `file` that `known` (the parsed configuration, serialised
/// again) does not have.
fn unknown_keys(file: &toml::Value, known: &toml::Value, prefix: &str, out: &mut Vec<String>) {
    let (toml::Value::Table(f), toml::Value::Table(k)) = (file, known) else {
        return;
    };
    for (key, v) in f {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        match k.get(key) {
            Some(kv) => unknown_keys(v, kv, &path, out),
            None => out.push(format!(
                "`{path}`{}",
                crate::suggest::did_you_mean(key, k.keys().map(String::as_str))
            )),
        }
    }
}

/// Switches of the command line applied on top of a configuration.
#[derive(Clone, Copy, Debug, Default)]
pub struct Switches {
    /// Turn MC-OR on with its default thresholds (unless the file configured it).
    pub mcor: bool,
    /// Turn AVC on with its default baseline (unless the file configured it).
    pub avc: bool,
    /// Emulated local-mapping lag in frames (`Config::mapping_lag`), overriding the file's.
    pub mapping_lag: Option<u32>,
    /// Turn loop closing off (ablation; it is part of the ORB-SLAM2 baseline).
    pub no_loop_closing: bool,
    /// MC-OR's cluster reading, overriding the file's (implies MC-OR on).
    pub mcor_cluster: Option<ClusterViews>,
    /// Turn on the rigid consensus (beyond the paper) with its defaults (unless the file
    /// configured it).
    pub rc: bool,
}

/// Applies the switches.
pub fn apply_switches(mut config: Config, s: Switches) -> Config {
    if (s.mcor || s.mcor_cluster.is_some()) && config.mcor.is_none() {
        config.mcor = Some(McorParams::default());
    }
    if let (Some(v), Some(m)) = (s.mcor_cluster, config.mcor.as_mut()) {
        m.cluster_views = v;
    }
    if s.avc && config.avc.is_none() {
        config.avc = Some(AvcParams::default());
    }
    if s.rc && config.rc.is_none() {
        config.rc = Some(RigidConsensusParams::default());
    }
    if let Some(n) = s.mapping_lag {
        config.mapping_lag = n;
    }
    if s.no_loop_closing {
        config.loop_closing.enabled = false;
    }
    config
}

/// The documented speed approximations `config` turns on, as their config-file settings
/// (`avc.aim = "direct"`, `mcor.view_stride = K`), sorted; empty: the reference every result
/// was made with. A sweep folder pins them, so approximate runs are never averaged with exact
/// ones.
pub fn approximations(config: &Config) -> Vec<String> {
    let mut a = Vec::new();
    if config.avc.as_ref().is_some_and(|a| a.aim == AvcAim::Direct) {
        a.push("avc.aim = \"direct\"".to_string());
    }
    if let Some(m) = config.mcor.as_ref().filter(|m| m.view_stride != 1) {
        a.push(format!("mcor.view_stride = {}", m.view_stride));
    }
    a.sort();
    a
}

/// The readings of the paper (issue 72) `config` sets away from their defaults, as their
/// config-file settings (`mcor.sightings = "all"`, `avc.gate = "3dof"`, `rgbd_baseline = 0.05`),
/// sorted; empty: the defaults every earlier result was made with. A sweep folder pins them.
pub fn readings(config: &Config) -> Vec<String> {
    let mut r = Vec::new();
    if let Some(m) = &config.mcor {
        let d = McorParams::default();
        if m.sightings != d.sightings {
            r.push(format!("mcor.sightings = {:?}", m.sightings.name()));
        }
        if m.verdict != d.verdict {
            r.push(format!("mcor.verdict = {:?}", m.verdict.name()));
        }
        if m.consensus_min_sightings != d.consensus_min_sightings {
            r.push(format!(
                "mcor.consensus_min_sightings = {}",
                m.consensus_min_sightings
            ));
        }
        if m.scope != d.scope {
            r.push(format!("mcor.scope = {:?}", m.scope.name()));
        }
        if m.depth_normalised != d.depth_normalised {
            r.push(format!("mcor.depth_normalised = {}", m.depth_normalised));
        }
    }
    if let Some(a) = &config.avc {
        let d = AvcParams::default();
        if a.gate != d.gate {
            r.push(format!("avc.gate = {:?}", a.gate.name()));
        }
        if a.b_role != d.b_role {
            r.push(format!("avc.b_role = {:?}", a.b_role.name()));
        }
    }
    if let Some(b) = config.rgbd_baseline {
        r.push(format!("rgbd_baseline = {b}"));
    }
    r.sort();
    r
}

/// The configuration name of the tables' columns: `orb`, `mcor`, `avc` or `mcor+avc` (MC-OR
/// with its default, every-frame cluster), or `mcor-keyframes` / `mcor-keyframes+avc` for
/// MC-OR's keyframe cluster reading.
pub fn config_name(c: &Config) -> &'static str {
    let keyframes = c
        .mcor
        .as_ref()
        .is_some_and(|m| m.cluster_views == ClusterViews::Keyframes);
    if c.rc.is_some() {
        return match (c.mcor.is_some(), c.avc.is_some()) {
            (false, false) => "rc",
            (false, true) => "rc+avc",
            (true, false) => "rc+mcor",
            (true, true) => "rc+mcor+avc",
        };
    }
    match (c.mcor.is_some(), c.avc.is_some(), keyframes) {
        (false, false, _) => "orb",
        (true, false, false) => "mcor",
        (false, true, _) => "avc",
        (true, true, false) => "mcor+avc",
        (true, false, true) => "mcor-keyframes",
        (true, true, true) => "mcor-keyframes+avc",
    }
}

/// The system run: the sensor's defaults, overlaid by the `--config` file, with the switches
/// of the command line; refused when the result is not a valid configuration.
pub fn system_config(
    sensor: slam_core::SensorKind,
    config_file: Option<&Path>,
    switches: Switches,
) -> Result<Config> {
    let mut config = base_config(sensor);
    if let Some(p) = config_file {
        config = overlay_file(&config, p)?;
    }
    let config = apply_switches(config, switches);
    config
        .check()
        .map_err(|e| anyhow::anyhow!("{e} (from the command line or --config)"))?;
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_misspelt_key_is_refused_with_the_key_meant() {
        let p = file(
            "typo",
            "[mcor]\ntau_mff = 0.3\n[tracking]\nlocal_ratioo = 1\nbogus = 2\n",
        );
        let e = format!("{:#}", overlay_file(&Config::default(), &p).unwrap_err());
        assert!(e.contains("`mcor.tau_mff` (did you mean `tau_mf`?)"), "{e}");
        assert!(
            e.contains("`tracking.local_ratioo` (did you mean `local_ratio`?)"),
            "{e}"
        );
        assert!(
            e.contains("`tracking.bogus`,") || e.contains("`tracking.bogus` ("),
            "{e}"
        );
        assert!(e.contains("noisefree config"), "{e}");
    }

    #[test]
    fn the_printed_defaults_are_a_file_that_reads_back_as_the_defaults() {
        for sensor in [SensorKind::Rgbd, SensorKind::Stereo] {
            let text = defaults_text(sensor).unwrap();
            for key in ["sightings", "verdict", "scope", "gate", "b_role", "tau_mf"] {
                assert!(text.contains(&format!("\n{key} = ")), "{key} in\n{text}");
            }
            let p = file(&format!("defaults-{sensor:?}"), &text);
            let read = overlay_file(&base_config(sensor), &p).unwrap();
            let mut expected = base_config(sensor);
            expected.mcor = Some(McorParams::default());
            expected.avc = Some(AvcParams::default());
            expected.rc = Some(RigidConsensusParams::default());
            assert_eq!(read, expected);
        }
    }

    fn file(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("nf-config-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(format!("{name}.toml"));
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn every_field_of_a_full_configuration_is_accepted() {
        let c = Config {
            mcor: Some(McorParams::default()),
            avc: Some(AvcParams::default()),
            ..Config::default()
        };
        let p = file("full", &toml::to_string(&c).unwrap());
        let read = overlay_file(&Config::default(), &p).unwrap();
        assert_eq!(config_name(&read), "mcor+avc");
    }

    #[test]
    fn the_cluster_reading_and_the_rigid_consensus_are_read_from_the_file() {
        let p = file("frames", "[mcor]\ncluster_views = \"every-frame\"\n");
        let c = overlay_file(&Config::default(), &p).unwrap();
        assert_eq!(config_name(&c), "mcor");
        let p = file("keyframes", "[mcor]\ncluster_views = \"keyframes\"\n");
        let c = overlay_file(&Config::default(), &p).unwrap();
        assert_eq!(config_name(&c), "mcor-keyframes");
        assert_eq!(c.mcor.unwrap().cluster_views, ClusterViews::Keyframes);
        // The view-stride approximation; the reference (1) when the file says nothing.
        let p = file("stride", "[mcor]\nview_stride = 2\n");
        let c = overlay_file(&Config::default(), &p).unwrap();
        assert_eq!(config_name(&c), "mcor");
        assert_eq!(c.mcor.unwrap().view_stride, 2);
        assert_eq!(McorParams::default().view_stride, 1);
        let p = file(
            "approx",
            "[mcor]\nview_stride = 3\n[avc]\naim = \"direct\"\n",
        );
        let c = overlay_file(&Config::default(), &p).unwrap();
        assert_eq!(
            approximations(&c),
            ["avc.aim = \"direct\"", "mcor.view_stride = 3"]
        );
        assert!(approximations(&Config::default()).is_empty());
        let p = file("rc", "[rc]\nhypotheses = 32\n");
        let c = overlay_file(&Config::default(), &p).unwrap();
        assert_eq!(config_name(&c), "rc");
        assert_eq!(c.rc.as_ref().unwrap().hypotheses, 32);
        assert_eq!(
            c.rc.unwrap().weight_cap,
            RigidConsensusParams::default().weight_cap
        );
        let p = file("badview", "[mcor]\ncluster_views = \"sometimes\"\n");
        let e = format!("{:#}", overlay_file(&Config::default(), &p).unwrap_err());
        assert!(e.contains("badview.toml"), "{e}");
        // The command line's switch overrides the file's reading.
        let c = apply_switches(
            Config::default(),
            Switches {
                mcor_cluster: Some(ClusterViews::Keyframes),
                rc: true,
                ..Switches::default()
            },
        );
        assert_eq!(config_name(&c), "rc+mcor");
        assert_eq!(c.mcor.unwrap().cluster_views, ClusterViews::Keyframes);
    }

    #[test]
    fn a_subset_overlays_the_defaults() {
        let p = file(
            "subset",
            "mapping_lag = 2\n[loop_closing]\nenabled = false\n",
        );
        let c = overlay_file(&Config::default(), &p).unwrap();
        assert_eq!(c.mapping_lag, 2);
        assert!(!c.loop_closing.enabled);
        assert_eq!(
            c.loop_closing.consistency,
            Config::default().loop_closing.consistency
        );
    }

    #[test]
    fn values_out_of_range_are_refused_with_their_range() {
        // Issue 45: this value once made a 6-frame run take 11.6 GB and 173 s.
        let p = file("shrink", "[orb]\nscale_factor = 0.5\n");
        let e = format!("{:#}", overlay_file(&Config::default(), &p).unwrap_err());
        assert!(e.contains("shrink.toml"), "{e}");
        assert!(e.contains("orb.scale_factor = 0.5: must be > 1"), "{e}");
        let p = file("nan", "[mcor]\ntau_mf = nan\n");
        let e = format!("{:#}", overlay_file(&Config::default(), &p).unwrap_err());
        assert!(e.contains("mcor.tau_mf = NaN: must be > 0"), "{e}");
    }

    #[test]
    fn misspelt_keys_are_refused_by_name() {
        let p = file("typo", "mapping_lagg = 2\n[loop_closing]\nenabld = false\n");
        let e = format!("{:#}", overlay_file(&Config::default(), &p).unwrap_err());
        assert!(e.contains("typo.toml"), "{e}");
        assert!(e.contains("`mapping_lagg`"), "{e}");
        assert!(e.contains("`loop_closing.enabld`"), "{e}");
    }
}
