//! Plain in-memory images handed to slam-core: 8-bit grey and metric depth, and the colour
//! image a grey one was converted from (carried for writers and colour-based consumers;
//! slam-core itself reads only grey). slam-core does no decoding; the dataset readers and the
//! synthetic generator fill these.

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

/// An 8-bit RGB image, row-major and interleaved, `data.len() == 3 * width * height`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColourImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major R, G, B triples.
    pub data: Vec<u8>,
}

impl ColourImage {
    /// The grey image a reader makes of it ([`rgb_to_gray`] per pixel).
    pub fn to_gray(&self) -> GrayImage {
        GrayImage {
            width: self.width,
            height: self.height,
            data: self
                .data
                .chunks_exact(3)
                .map(|p| rgb_to_gray(p[0], p[1], p[2]))
                .collect(),
        }
    }
}

/// BT.601 luma in 14-bit fixed point with rounding (the constants OpenCV uses), so grey values
/// match what ORB-SLAM2 sees for the same colour image; grey (v, v, v) gives v.
#[inline]
pub fn rgb_to_gray(r: u8, g: u8, b: u8) -> u8 {
    ((r as u32 * 4899 + g as u32 * 9617 + b as u32 * 1868 + (1 << 13)) >> 14) as u8
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
    /// The colour image `image` is the grey of (`image == colour.to_gray()`), when the source
    /// has colour (TUM RGB-D folders, synthetic RGB-D); kept so a perturbed or exported copy
    /// stays in colour. slam-core does not read it.
    pub colour: Option<std::sync::Arc<ColourImage>>,
}

impl FrameInput {
    /// The frame without its colour image (what tracking needs; a reader that holds many
    /// frames drops it to save 3 bytes a pixel).
    pub fn without_colour(mut self) -> FrameInput {
        self.colour = None;
        self
    }
}
