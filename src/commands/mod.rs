//! One module per subcommand: its clap arguments and its `run` function; `shared_args` holds
//! the argument groups several of them flatten in.

pub mod analyze;
pub mod bench;
pub mod config;
pub mod eval;
pub mod features;
pub mod fetch;
pub mod match_level;
pub mod perturb;
pub mod plot;
pub mod regress;
pub mod report;
pub mod run;
pub mod settings;
pub mod shared_args;
pub mod sweep;
pub mod synth;
pub mod table;
pub mod view;
pub mod vocab;
