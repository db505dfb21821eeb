//! Place recognition benchmarks: the BoW transform of a 1000-feature frame, a keyframe-database
//! query over 1000 keyframes, and loading a 10^6-word vocabulary (k 10, L 6, ORBvoc.txt's size)
//! from DBoW2's text form and from our binary form.

use criterion::{criterion_group, criterion_main, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slam_core::data::KeyFrameId;
use slam_core::feature::Descriptor;
use slam_core::place::vocabulary::NodeRecord;
use slam_core::place::{BowVector, KeyFrameDatabase, Vocabulary, Weighting};
use std::hint::black_box;

fn descriptor(rng: &mut ChaCha8Rng) -> Descriptor {
    [rng.random(), rng.random(), rng.random(), rng.random()]
}

/// A full tree of k = 10, L = 6 (1,111,110 nodes, 10^6 words) with random centroids: the shape
/// and size of ORBvoc.txt.
fn full_vocabulary() -> Vocabulary {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let (k, levels) = (10usize, 6usize);
    let mut records = Vec::new();
    // Breadth-first: the nodes of depth d are a contiguous run; children follow in order.
    let mut level_start = 0usize; // index of the first node of the previous level (0 = root)
    let mut level_len = 1usize;
    for depth in 1..=levels {
        let first_new = records.len() + 1;
        for p in 0..level_len {
            let parent = if depth == 1 {
                0
            } else {
                (level_start + p) as u32
            };
            for _ in 0..k {
                records.push(NodeRecord {
                    parent,
                    is_leaf: depth == levels,
                    descriptor: descriptor(&mut rng),
                    weight: if depth == levels {
                        rng.random::<f64>() * 5.0
                    } else {
                        0.0
                    },
                });
            }
        }
        level_start = first_new;
        level_len *= k;
    }
    Vocabulary::from_nodes(k, levels, Weighting::TfIdf, &records).unwrap()
}

fn place(c: &mut Criterion) {
    let voc = full_vocabulary();
    assert_eq!(voc.word_count(), 1_000_000);
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let frame: Vec<Descriptor> = (0..1000).map(|_| descriptor(&mut rng)).collect();
    c.bench_function("bow transform, 1000 features, 10^6 words", |b| {
        b.iter(|| voc.transform(black_box(&frame), 4))
    });
    // 1000 keyframes of 1000 features each (the shipped vocabulary's size class would give
    // more shared words; this tree's random words give fewer).
    let bows: Vec<BowVector> = (0..1000)
        .map(|_| {
            let d: Vec<Descriptor> = (0..1000).map(|_| descriptor(&mut rng)).collect();
            voc.transform(&d, 4).0
        })
        .collect();
    let mut db = KeyFrameDatabase::new(voc.word_count());
    for (i, b) in bows.iter().enumerate() {
        db.add(KeyFrameId(i as u32), b);
    }
    let (q, _) = voc.transform(&frame, 4);
    c.bench_function("database relocalization query, 1000 keyframes", |b| {
        b.iter(|| {
            db.relocalization_candidates(
                black_box(&q),
                |k| Some(&bows[k.index()]),
                |_, _| Vec::new(),
            )
        })
    });
    let text = voc.to_text();
    let binary = voc.to_binary();
    let mut g = c.benchmark_group("vocabulary load, 10^6 words");
    g.sample_size(10);
    g.bench_function("DBoW2 text", |b| {
        b.iter(|| Vocabulary::from_text(black_box(&text)).unwrap())
    });
    g.bench_function("binary", |b| {
        b.iter(|| Vocabulary::from_binary(black_box(&binary)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, place);
criterion_main!(benches);
