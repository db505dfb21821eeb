//! Tests of the place-recognition layer on synthetic "places": sets of random descriptors, seen
//! again with bit noise and some features replaced, as a revisit sees a place.

use super::*;
use crate::data::KeyFrameId;
use crate::feature::Descriptor;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn random_descriptor(rng: &mut ChaCha8Rng) -> Descriptor {
    [rng.random(), rng.random(), rng.random(), rng.random()]
}

/// `n` places of `per` descriptors each.
fn places(n: usize, per: usize, seed: u64) -> Vec<Vec<Descriptor>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| (0..per).map(|_| random_descriptor(&mut rng)).collect())
        .collect()
}

/// A view of a place: every descriptor with `flips` random bits flipped, and a fraction
/// `replaced` of them swapped for unrelated descriptors.
fn view(place: &[Descriptor], flips: usize, replaced: f64, seed: u64) -> Vec<Descriptor> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    place
        .iter()
        .map(|d| {
            if rng.random::<f64>() < replaced {
                return random_descriptor(&mut rng);
            }
            let mut d = *d;
            for _ in 0..flips {
                let b = rng.random_range(0..256);
                d[b / 64] ^= 1 << (b % 64);
            }
            d
        })
        .collect()
}

fn trained(places: &[Vec<Descriptor>]) -> Vocabulary {
    let images: Vec<Vec<Descriptor>> = places
        .iter()
        .enumerate()
        .flat_map(|(i, p)| {
            [
                view(p, 8, 0.1, 1000 + i as u64),
                view(p, 8, 0.1, 2000 + i as u64),
            ]
        })
        .collect();
    let params = TrainParams {
        k: 8,
        levels: 4,
        seed: 7,
        ..TrainParams::default()
    };
    train(&images, &params, &|_| {}).unwrap()
}

#[test]
fn a_view_scores_one_against_itself_and_its_place_above_other_places() {
    let ps = places(40, 200, 1);
    let voc = trained(&ps);
    assert!(voc.word_count() > 1000, "{} words", voc.word_count());
    for (i, p) in ps.iter().enumerate().take(10) {
        let (a, _) = voc.transform(&view(p, 10, 0.2, 10 + i as u64), 4);
        let (b, _) = voc.transform(&view(p, 10, 0.2, 20 + i as u64), 4);
        assert!((score_l1(&a, &a) - 1.0).abs() < 1e-12);
        let same = score_l1(&a, &b);
        for (j, q) in ps.iter().enumerate() {
            if j != i {
                let (c, _) = voc.transform(&view(q, 10, 0.2, 30 + j as u64), 4);
                assert!(same > score_l1(&a, &c), "place {i}: {same} vs place {j}");
            }
        }
    }
}

#[test]
fn database_returns_the_revisited_place_among_hundreds() {
    // The vocabulary knows 40 places; the database holds 400 keyframes of other places too.
    let ps = places(400, 200, 2);
    let voc = trained(&ps[..40]);
    let bows: Vec<BowVector> = ps
        .iter()
        .enumerate()
        .map(|(i, p)| voc.transform(&view(p, 8, 0.1, 5000 + i as u64), 4).0)
        .collect();
    let mut db = KeyFrameDatabase::new(voc.word_count());
    for (i, b) in bows.iter().enumerate() {
        db.add(KeyFrameId(i as u32), b);
    }
    let no_covisibility = |_: KeyFrameId, _: usize| Vec::new();
    for target in [3usize, 77, 150, 399] {
        let (q, _) = voc.transform(&view(&ps[target], 12, 0.3, 9000 + target as u64), 4);
        let c = db.relocalization_candidates(&q, |k| Some(&bows[k.index()]), no_covisibility);
        assert_eq!(
            c.first(),
            Some(&KeyFrameId(target as u32)),
            "target {target}: {c:?}"
        );
    }
    // Erasing the keyframe makes it unfindable.
    db.erase(KeyFrameId(77), &bows[77]);
    let (q, _) = voc.transform(&view(&ps[77], 12, 0.3, 9077), 4);
    let c = db.relocalization_candidates(&q, |k| Some(&bows[k.index()]), no_covisibility);
    assert!(!c.contains(&KeyFrameId(77)));
}

#[test]
fn covisible_groups_accumulate_and_return_their_best_keyframe() {
    use database::{group_best, Candidate};
    let c = |k: u32, s: f64| Candidate {
        keyframe: KeyFrameId(k),
        common_words: 10,
        score: s,
    };
    // KF 1, 2, 3 see each other (0.2 + 0.3 + 0.25 = 0.75); KF 9 alone scores 0.4.
    let scored = vec![c(1, 0.2), c(2, 0.3), c(3, 0.25), c(9, 0.4)];
    let covis = |k: KeyFrameId, _: usize| match k.0 {
        1 => vec![KeyFrameId(2), KeyFrameId(3)],
        2 => vec![KeyFrameId(1), KeyFrameId(3)],
        3 => vec![KeyFrameId(2), KeyFrameId(1)],
        _ => vec![],
    };
    // The group's best (KF 2) comes first; KF 9's 0.4 is below 0.75 x 0.75.
    assert_eq!(group_best(&scored, covis), vec![KeyFrameId(2)]);
}

#[test]
fn direct_index_groups_features_of_the_same_node() {
    let ps = places(20, 200, 3);
    let voc = trained(&ps);
    let a = view(&ps[5], 0, 0.0, 1);
    let (_, fa) = voc.transform(&a, 2);
    // Level 4 - 2 = 2: at most 8^2 nodes; every feature is in exactly one group.
    assert!(fa.nodes().len() <= 64);
    let mut all: Vec<usize> = fa.nodes().iter().flat_map(|(_, f)| f.clone()).collect();
    all.sort_unstable();
    assert_eq!(all, (0..a.len()).collect::<Vec<_>>());
    // True correspondences (same index) of a noisy view share a node far more often than the
    // 1/64 of chance (uniformly random descriptors sit near the boundaries of every cell, so
    // this is the hard case; ORB descriptors cluster).
    let b = view(&ps[5], 3, 0.0, 2);
    let (_, fb) = voc.transform(&b, 2);
    let mut together = 0;
    for (x, y) in fa.common_nodes(&fb) {
        together += x.iter().filter(|i| y.binary_search(i).is_ok()).count();
    }
    assert!(
        together as f64 > 0.6 * a.len() as f64,
        "{together} of {}",
        a.len()
    );
}

#[test]
fn text_and_binary_forms_round_trip_and_give_identical_bow_vectors() {
    let ps = places(10, 150, 4);
    let voc = trained(&ps);
    let text = voc.to_text();
    assert!(text.starts_with("8 4 0 0\n"), "{}", &text[..20]);
    let from_text = Vocabulary::from_text(&text).unwrap();
    let from_bin = Vocabulary::from_binary(&voc.to_binary()).unwrap();
    assert_eq!(from_bin, voc);
    // Text weights are printed shortest-exact, so the text form is exact too.
    assert_eq!(from_text, voc);
    let q = view(&ps[2], 10, 0.2, 3);
    assert_eq!(from_text.transform(&q, 2), from_bin.transform(&q, 2));
}

/// A vocabulary written by hand in DBoW2's text format: k = 2, L = 2, four words.
const HAND_WRITTEN: &str = "2 2 0 0
0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0
0 0 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 0
1 1 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0.5
1 1 15 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 1.25
2 1 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 2
2 1 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 255 0 0.75
";

#[test]
fn reads_a_file_written_in_dbow2_text_format() {
    let voc = Vocabulary::from_text(HAND_WRITTEN).unwrap();
    assert_eq!(
        (voc.k(), voc.levels(), voc.word_count(), voc.node_count()),
        (2, 2, 4, 7)
    );
    assert_eq!(voc.weighting(), Weighting::TfIdf);
    // Words are numbered in node order: nodes 3, 4, 5, 6.
    assert_eq!(voc.word_weight(1), 1.25);
    // Low bits set: closer to node 1 (zeros), then to node 4 (byte 0 = 15) than node 3.
    let d: Descriptor = [0x0f, 0, 0, 0];
    assert_eq!(voc.quantize(&d, 1), (1, 1));
    // All ones but the last byte: node 2's side, word 3 (node 6).
    let mut d = [u64::MAX; 4];
    d[3] &= !(0xffu64 << 56);
    assert_eq!(voc.quantize(&d, 1), (3, 2));
    // Byte order: byte 31 is the top byte of word 3.
    let bytes = vocabulary::descriptor_to_bytes(&d);
    assert_eq!((bytes[0], bytes[31]), (255, 0));
    assert_eq!(Vocabulary::from_text(&voc.to_text()).unwrap(), voc);
}

#[test]
fn malformed_text_names_the_line() {
    let e = Vocabulary::from_text("10 6 0\n").unwrap_err();
    assert_eq!(e.line, 1);
    let e = Vocabulary::from_text("2 2 3 0\n").unwrap_err();
    assert!(e.message.contains("scoring 3"), "{e}");
    let mut lines: Vec<&str> = HAND_WRITTEN.lines().collect();
    lines[4] = "1 1 15 0 0 0";
    let e = Vocabulary::from_text(&lines.join("\n")).unwrap_err();
    assert_eq!(e.line, 5, "{e}");
    lines[4] = "9 1 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 1";
    let e = Vocabulary::from_text(&lines.join("\n")).unwrap_err();
    assert_eq!(e.line, 5, "{e}");
    assert!(e.message.contains("parent 9"), "{e}");
    lines[4] = "1 1 300 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 1";
    assert_eq!(
        Vocabulary::from_text(&lines.join("\n")).unwrap_err().line,
        5
    );
}

#[test]
fn corrupt_binary_is_refused() {
    let voc = Vocabulary::from_text(HAND_WRITTEN).unwrap();
    let mut b = voc.to_binary();
    assert_eq!(Vocabulary::from_binary(&b).unwrap(), voc);
    b[30] ^= 1;
    let e = Vocabulary::from_binary(&b).unwrap_err();
    assert!(e.message.contains("checksum"), "{e}");
    assert!(Vocabulary::from_binary(b"not a vocabulary at all")
        .unwrap_err()
        .message
        .contains("magic"));
}

#[test]
fn training_is_deterministic_whatever_the_thread_count() {
    let ps = places(12, 150, 5);
    let images: Vec<Vec<Descriptor>> = ps.iter().map(|p| view(p, 4, 0.0, 1)).collect();
    let params = TrainParams {
        k: 6,
        levels: 3,
        seed: 11,
        ..TrainParams::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| train(&images, &params, &|_| {}).unwrap().to_binary())
    };
    let a = run(1);
    assert_eq!(a, run(3));
    let other = TrainParams {
        seed: 12,
        ..params.clone()
    };
    assert_ne!(a, train(&images, &other, &|_| {}).unwrap().to_binary());
    // The progress callback sees every descriptor once.
    let seen = std::sync::atomic::AtomicUsize::new(0);
    train(&images, &params, &|n| {
        seen.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    assert_eq!(seen.into_inner(), 12 * 150);
}
