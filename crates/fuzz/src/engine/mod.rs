//! The fuzzing engine, on the standard library alone: a seeded generator ([`rng`]), the
//! mutator ([`mutate`]), a counting allocator ([`alloc`]) and the loop that judges a reader
//! ([`driver`]). Having no dependency lets the `noisefree` binary crate's own tests include
//! these files by path for the formats whose readers live in the binary (runs.csv, the config
//! TOML, the golden file), since that crate cannot depend on this one.

pub mod alloc;
pub mod driver;
pub mod mutate;
pub mod rng;
