//! `noisefree synth` (being written).

/// Arguments of `noisefree synth`.
#[derive(clap::Args, Debug)]
pub struct SynthArgs {}

/// Runs `noisefree synth`.
pub fn run(_args: SynthArgs) -> anyhow::Result<()> {
    anyhow::bail!("`noisefree synth` is not implemented yet")
}
