//! The columns of a sweep's tables: noisefree's configurations ([`ConfigKind`]: the paper's
//! four, MC-OR's explicit readings, the rigid consensus) and external SLAM programs by name
//! ([`RunConfig`]). Below both the sweep and the external systems, which must refuse a system
//! named like one of ours.

use anyhow::{bail, Result};
use slam_core::system::ClusterViews;
use std::fmt;

/// The paper's four columns of Table III (`mcor` and `mcor+avc` with the folder's MC-OR cluster
/// reading, every frame by default), columns that name MC-OR's reading explicitly, and
/// noisefree's rigid consensus.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ConfigKind {
    /// ORB-SLAM2 baseline (both techniques off).
    Orb,
    /// w/ MC-OR.
    Mcor,
    /// w/ AVC.
    Avc,
    /// w/ MC-OR + AVC.
    McorAvc,
    /// w/ MC-OR, clusters built from every frame that matched the point.
    McorFrames,
    /// w/ MC-OR (every-frame clusters) + AVC.
    McorFramesAvc,
    /// w/ MC-OR, clusters built from the observing keyframes only (the default before issue 18).
    McorKeyframes,
    /// w/ MC-OR (keyframe clusters) + AVC.
    McorKeyframesAvc,
    /// noisefree's rigid consensus (beyond the paper), neither MC-OR nor AVC.
    Rc,
}

impl ConfigKind {
    /// Every kind in the paper's column order.
    pub const ALL: [ConfigKind; 4] = [
        ConfigKind::Orb,
        ConfigKind::Mcor,
        ConfigKind::Avc,
        ConfigKind::McorAvc,
    ];

    /// Every kind, the paper's four first (the column order of the tables).
    pub const EVERY: [ConfigKind; 9] = [
        ConfigKind::Orb,
        ConfigKind::Mcor,
        ConfigKind::Avc,
        ConfigKind::McorAvc,
        ConfigKind::McorFrames,
        ConfigKind::McorFramesAvc,
        ConfigKind::McorKeyframes,
        ConfigKind::McorKeyframesAvc,
        ConfigKind::Rc,
    ];

    /// Command-line / CSV spelling.
    pub fn name(self) -> &'static str {
        match self {
            ConfigKind::Orb => "orb",
            ConfigKind::Mcor => "mcor",
            ConfigKind::Avc => "avc",
            ConfigKind::McorAvc => "mcor+avc",
            ConfigKind::McorFrames => "mcor-frames",
            ConfigKind::McorFramesAvc => "mcor-frames+avc",
            ConfigKind::McorKeyframes => "mcor-keyframes",
            ConfigKind::McorKeyframesAvc => "mcor-keyframes+avc",
            ConfigKind::Rc => "rc",
        }
    }

    /// Parses the command-line spelling.
    pub fn parse(s: &str) -> Result<ConfigKind> {
        Ok(match s.trim() {
            "orb" | "orb-slam2" | "baseline" => ConfigKind::Orb,
            "mcor" => ConfigKind::Mcor,
            "avc" => ConfigKind::Avc,
            "mcor+avc" | "avc+mcor" => ConfigKind::McorAvc,
            "mcor-frames" => ConfigKind::McorFrames,
            "mcor-frames+avc" | "avc+mcor-frames" => ConfigKind::McorFramesAvc,
            "mcor-keyframes" => ConfigKind::McorKeyframes,
            "mcor-keyframes+avc" | "avc+mcor-keyframes" => ConfigKind::McorKeyframesAvc,
            "rc" => ConfigKind::Rc,
            other => bail!(
                "unknown configuration {other:?}{}; expected orb, mcor, avc, mcor+avc, \
                 mcor-frames, mcor-frames+avc, mcor-keyframes, mcor-keyframes+avc or rc, \
                 each with readings if wanted (mcor:sightings=all)",
                crate::suggest::did_you_mean(other, ConfigKind::EVERY.map(ConfigKind::name))
            ),
        })
    }

    /// Whether MC-OR is on.
    pub fn mcor(self) -> bool {
        matches!(
            self,
            ConfigKind::Mcor
                | ConfigKind::McorAvc
                | ConfigKind::McorFrames
                | ConfigKind::McorFramesAvc
                | ConfigKind::McorKeyframes
                | ConfigKind::McorKeyframesAvc
        )
    }

    /// Whether the rigid consensus (beyond the paper) is on.
    pub fn rc(self) -> bool {
        self == ConfigKind::Rc
    }

    /// MC-OR's cluster reading this kind names; `None`: the configuration's (every frame
    /// unless a config file says otherwise).
    pub fn cluster_views(self) -> Option<ClusterViews> {
        match self {
            ConfigKind::McorFrames | ConfigKind::McorFramesAvc => Some(ClusterViews::EveryFrame),
            ConfigKind::McorKeyframes | ConfigKind::McorKeyframesAvc => {
                Some(ClusterViews::Keyframes)
            }
            _ => None,
        }
    }

    /// Whether AVC is on.
    pub fn avc(self) -> bool {
        matches!(
            self,
            ConfigKind::Avc
                | ConfigKind::McorAvc
                | ConfigKind::McorFramesAvc
                | ConfigKind::McorKeyframesAvc
        )
    }
}

impl fmt::Display for ConfigKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What a run runs: one of noisefree's configurations, or an external SLAM program declared in
/// the config file (`[systems.NAME]`, see `crate::external`), by its name.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RunConfig {
    /// noisefree in one of its configurations.
    Ours(ConfigKind),
    /// noisefree in one of its configurations under readings of the paper (parsed and applied
    /// in `crate::readings`, above this module): the kind, and the column's canonical name
    /// (`mcor:sightings=all`).
    Reading {
        /// The configuration the readings apply to.
        kind: ConfigKind,
        /// The canonical name, readings included.
        name: String,
    },
    /// An external system, by the name of its definition.
    System(String),
}

impl RunConfig {
    /// The name in `runs.csv` and on the command line.
    pub fn name(&self) -> &str {
        match self {
            RunConfig::Ours(k) => k.name(),
            RunConfig::Reading { name, .. } => name,
            RunConfig::System(s) => s,
        }
    }

    /// noisefree's configuration kind, `None` for an external system.
    pub fn kind(&self) -> Option<ConfigKind> {
        match self {
            RunConfig::Ours(k) => Some(*k),
            RunConfig::Reading { kind, .. } => Some(*kind),
            RunConfig::System(_) => None,
        }
    }
}
