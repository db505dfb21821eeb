//! Prints each twin's motion as solved (smooth speeds against TUM's figures, frame-to-frame
//! speeds, shake amplitudes, exposure samples) and, given a folder, writes a contact sheet per
//! twin into it: `cargo run --release -p synth --example twins -- [DIR] [SEED] [TWINS]`
//! (TWINS: comma-separated twin names to write sheets of; all when absent).

use synth::catalog::twins::{config, frames, path, TWINS};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = args.get(1).map(std::path::PathBuf::from);
    let seed: u64 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let only: Option<Vec<&str>> = args.get(3).map(|s| s.split(',').collect());
    println!(
        "| twin | imitates | s | frames | m/s (TUM) | deg/s (TUM) | frame m/s | frame deg/s | shake mm / deg RMS | blur samples |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for t in &TWINS {
        let p = path(t);
        let (v, w) = p.smooth_speeds();
        let (fv, fw) = p.frame_speeds(t.camera.camera().fps);
        let (tp, ta) = p.tremor_rms();
        let c = config(t);
        println!(
            "| {} | {} | {:.1} | {} | {:.3} ({:.3}) | {:.2} ({:.2}) | {:.3} | {:.2} | {:.2} / {:.3} | {} |",
            t.name,
            t.imitates,
            t.duration_s,
            frames(t),
            v,
            t.mean_speed,
            w.to_degrees(),
            t.mean_angular_deg,
            fv,
            fw.to_degrees(),
            tp * 1e3,
            ta.to_degrees(),
            c.imaging.exposure.as_ref().map_or(0, |e| e.samples)
        );
        let wanted = only.as_ref().is_none_or(|o| o.contains(&t.name));
        if let (Some(d), true) = (&dir, wanted) {
            std::fs::create_dir_all(d)?;
            let gen = synth::Generator::try_new(c, seed)?;
            let out = d.join(format!("contact_{}.jpg", t.name));
            synth::write_contact_sheet(&gen, frames(t), 4, &out)?;
            eprintln!("wrote {}", out.display());
        }
    }
    Ok(())
}
