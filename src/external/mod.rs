//! Other SLAM systems in the same sweep: a program declared in the config file
//! (`[systems.NAME]`, [`system`]) runs as a configuration beside ours, on the same sequences
//! and seeds, given the sequence on disk with a settings file written from its camera
//! ([`export`]), watched as a child process ([`process`]) and scored as our runs are (`crate::sweep::external_run`).

pub mod export;
pub mod process;
pub use results::systems as system;
