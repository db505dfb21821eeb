//! `noisefree config`: every setting of the config TOML with its default, for one sensor, as a
//! file to start from (what `--config FILE` overlays; a key it does not list is refused).

use anyhow::Result;
use clap::Args;
use slam_core::SensorKind;

/// Arguments of `noisefree config`.
#[derive(Args, Debug)]
pub struct ConfigArgs {
    /// The sensor whose defaults to print: `rgbd` (ORB-SLAM2's TUM settings) or `stereo`
    /// (its EuRoC settings).
    #[arg(long, default_value = "rgbd", value_parser = ["rgbd", "stereo"])]
    pub sensor: String,
}

/// Prints the defaults.
pub fn run(args: ConfigArgs) -> Result<()> {
    let sensor = match args.sensor.as_str() {
        "stereo" => SensorKind::Stereo,
        _ => SensorKind::Rgbd,
    };
    print!("{}", crate::config_file::defaults_text(sensor)?);
    Ok(())
}
