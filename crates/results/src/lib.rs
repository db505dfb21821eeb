//! results: one noisefree results folder, read and written in one place, and the report over
//! it. A sweep writes its runs here; `noisefree table`, `report` and `plot` read them here.
//!
//! The folder:
//! - [`store`]: the run records (`runs.csv`), the folder's pinned settings
//!   (`sweep-settings.toml`) and the lock that lets several processes append;
//! - [`keys`]: a run's parameters, its key in the records, and the shard it belongs to;
//! - [`planned`]: the runs a sweep planned (`planned-runs.txt`), so a table knows a folder is
//!   complete;
//! - [`cost`]: what the runs cost (`cost.csv`);
//! - [`systems`]: the external SLAM programs a folder ran (`systems.toml`, pinned);
//! - [`columns`] and [`readings`]: what a column of the tables is (our configurations, their
//!   readings of the paper, external systems); [`spread`]: cells whose runs are one run.
//!
//! The report ([`report`]): the paper's tables, the statistics against the baseline, the
//! figures, the findings and each folder's index. Nothing here runs a SLAM system.

pub mod columns;
pub mod cost;
pub mod keys;
pub mod planned;
pub mod readings;
pub mod report;
pub mod spread;
pub mod store;
pub mod suggest;
pub mod systems;
