//! `noisefree eval` (being written).

/// Arguments of `noisefree eval`.
#[derive(clap::Args, Debug)]
pub struct EvalArgs {}

/// Runs `noisefree eval`.
pub fn run(_args: EvalArgs) -> anyhow::Result<()> {
    anyhow::bail!("`noisefree eval` is not implemented yet")
}
