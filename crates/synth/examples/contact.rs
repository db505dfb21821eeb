//! Writes a contact sheet of a preset and prints the generation speed:
//! `cargo run -p synth --example contact -- PRESET FRAMES OUT.png [SEED]`.

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let preset = args.get(1).map(String::as_str).unwrap_or("kinect");
    let n: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(300);
    let out = args.get(3).map(String::as_str).unwrap_or("contact.png");
    let seed: u64 = args.get(4).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let t0 = Instant::now();
    let gen = synth::Generator::try_new(synth::SynthConfig::preset(preset)?, seed)?;
    println!("scene built in {:.0} ms", t0.elapsed().as_secs_f64() * 1e3);
    let t1 = Instant::now();
    let k = 10;
    for i in 0..k {
        std::hint::black_box(gen.frame(i * n / k));
    }
    let dt = t1.elapsed().as_secs_f64() / k as f64;
    println!(
        "{preset}: {:.1} ms/frame ({:.1} frames/s)",
        dt * 1e3,
        1.0 / dt
    );
    synth::write_contact_sheet(&gen, n, 4, std::path::Path::new(out))?;
    println!("wrote {out}");
    Ok(())
}
