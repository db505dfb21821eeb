//! `noisefree fetch` (being written).

/// Arguments of `noisefree fetch`.
#[derive(clap::Args, Debug)]
pub struct FetchArgs {}

/// Runs `noisefree fetch`.
pub fn run(_args: FetchArgs) -> anyhow::Result<()> {
    anyhow::bail!("`noisefree fetch` is not implemented yet")
}
