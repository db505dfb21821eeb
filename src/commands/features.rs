//! `noisefree features` (being written).

/// Arguments of `noisefree features`.
#[derive(clap::Args, Debug)]
pub struct FeaturesArgs {}

/// Runs `noisefree features`.
pub fn run(_args: FeaturesArgs) -> anyhow::Result<()> {
    anyhow::bail!("`noisefree features` is not implemented yet")
}
