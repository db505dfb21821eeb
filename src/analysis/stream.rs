//! Frames of a synthetic sequence, rendered in parallel chunks and handed out in order: the
//! analyses need each frame's noiseless depth next to the noisy one, and holding a whole
//! sequence of both (about 2.7 MB a frame) would take gigabytes on long runs.

use rayon::prelude::*;
use slam_core::FrameInput;
use std::sync::Arc;
use synth::{Generator, SynthFrame};

/// Frames rendered at once (in parallel) before they are handed out.
pub const CHUNK: usize = 8;

/// The [`FrameInput`] a SLAM system sees for `frame` (grey image, measured depth or right
/// image), sharing nothing with `frame`'s ground-truth fields.
pub fn frame_input(frame: &SynthFrame) -> FrameInput {
    FrameInput {
        timestamp: frame.timestamp,
        image: Arc::new(frame.gray.clone()),
        depth: frame.depth.clone().map(Arc::new),
        right: frame.right.clone().map(Arc::new),
        colour: None,
    }
}

/// Calls `f` with consecutive chunks of up to [`CHUNK`] frames covering 0..n of `generator`,
/// in order; the frames of a chunk are rendered in parallel.
pub fn for_each_chunk(generator: &Generator, n: usize, mut f: impl FnMut(Vec<SynthFrame>)) {
    let mut start = 0;
    while start < n {
        let end = (start + CHUNK).min(n);
        f((start..end)
            .into_par_iter()
            .map(|i| generator.frame(i))
            .collect());
        start = end;
    }
}

/// Calls `f` with frames 0..n of `generator`, in order (rendered [`CHUNK`] at a time).
pub fn for_each_frame(generator: &Generator, n: usize, mut f: impl FnMut(SynthFrame)) {
    for_each_chunk(generator, n, |chunk| chunk.into_iter().for_each(&mut f));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_come_in_order_and_match_random_access() {
        let mut config = synth::SynthConfig::preset("kinect").unwrap();
        config.camera.width = 64;
        config.camera.height = 48;
        config.camera.cx = 32.0;
        config.camera.cy = 24.0;
        let generator = Generator::new(config, 3);
        let mut seen = Vec::new();
        for_each_frame(&generator, CHUNK + 3, |f| seen.push(f));
        assert_eq!(
            seen.iter().map(|f| f.index).collect::<Vec<_>>(),
            (0..CHUNK + 3).collect::<Vec<_>>()
        );
        let again = generator.frame(CHUNK + 1);
        assert_eq!(seen[CHUNK + 1].gray.data, again.gray.data);
        let input = frame_input(&again);
        assert_eq!(input.timestamp, again.timestamp);
        assert_eq!(
            input.depth.as_ref().map(|d| d.data.len()),
            again.depth.as_ref().map(|d| d.data.len())
        );
    }
}
