//! Plain in-memory images handed to slam-core: 8-bit grey and metric depth. slam-core does no
//! decoding; the dataset readers and the synthetic generator fill these.

/// An 8-bit grey image, row-major, `data.len() == width * height`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GrayImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major intensities.
    pub data: Vec<u8>,
}

impl GrayImage {
    /// A black image of the given size.
    pub fn new(width: usize, height: usize) -> Self {
        GrayImage {
            width,
            height,
            data: vec![0; width * height],
        }
    }

    /// Intensity at (x, y); the caller keeps (x, y) inside the image.
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> u8 {
        self.data[y * self.width + x]
    }
}

/// A depth image in metres, row-major; 0 (or any non-finite / non-positive value) means "no depth".
#[derive(Clone, Debug, PartialEq)]
pub struct DepthImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major depths in metres.
    pub data: Vec<f32>,
}

impl DepthImage {
    /// An all-invalid depth image of the given size.
    pub fn new(width: usize, height: usize) -> Self {
        DepthImage {
            width,
            height,
            data: vec![0.0; width * height],
        }
    }

    /// Depth at (x, y) in metres, or `None` when invalid; the caller keeps (x, y) inside.
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> Option<f32> {
        let d = self.data[y * self.width + x];
        (d.is_finite() && d > 0.0).then_some(d)
    }
}

/// What a sensor delivers for one frame: a grey (left) image plus either a registered depth
/// image (RGB-D) or a rectified right image (stereo).
#[derive(Clone, Debug)]
pub struct FrameInput {
    /// Capture time in seconds.
    pub timestamp: f64,
    /// Grey (left) image.
    pub image: std::sync::Arc<GrayImage>,
    /// Registered depth in metres (RGB-D only).
    pub depth: Option<std::sync::Arc<DepthImage>>,
    /// Rectified right image (stereo only).
    pub right: Option<std::sync::Arc<GrayImage>>,
}
