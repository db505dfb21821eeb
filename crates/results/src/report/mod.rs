//! What a sweep's run records become: the paper's tables, the resilience and ablation tables,
//! the statistics they state, the figures, and the folder index that links them.
//!
//! Layers, lowest first: `stats` and `markdown` (no report imports), then `figures` (and `panels`, the analyses' drawings), then the
//! tables (`tables`, `resilience`, `ablation`, `versus`), then `folder`, which writes them all.

pub mod ablation;
pub mod contact_sheet;
pub mod figures;
pub mod findings;
pub mod folder;
pub mod fps;
pub mod markdown;
pub mod panels;
pub mod readings;
pub mod resilience;
pub mod stats;
pub mod tables;
pub mod versus;
