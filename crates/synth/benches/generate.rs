//! Frames generated per second at the preset's resolution (640x480; stereo 752x480, two
//! images) for each preset, using all cores (rayon).
//! Run: `cargo bench -p synth --bench generate`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use synth::{preset_names, Generator, SynthConfig};

fn bench_presets(c: &mut Criterion) {
    let mut g = c.benchmark_group("synth_frame");
    g.sample_size(10);
    g.warm_up_time(std::time::Duration::from_secs(1));
    g.measurement_time(std::time::Duration::from_secs(4));
    g.throughput(Throughput::Elements(1));
    for name in preset_names() {
        let cfg = SynthConfig::preset(name).expect("preset exists");
        let gen = Generator::new(cfg, 1);
        let mut i = 0usize;
        g.bench_function(*name, |b| {
            b.iter(|| {
                i += 1;
                gen.frame(i)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_presets);
criterion_main!(benches);
