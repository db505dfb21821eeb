//! The one error type of the crate. Every variant names the file (and line, where there is one)
//! so a user can find what is wrong with their data; nothing in this crate panics on user data.

use std::path::PathBuf;

/// What went wrong while reading a dataset, the catalog, or fetching a sequence.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// An I/O error on a file or folder.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A required file or folder does not exist.
    #[error("{}: not found ({what})", path.display())]
    Missing {
        /// The missing path.
        path: PathBuf,
        /// What it should have been, e.g. "the TUM RGB-D image list".
        what: String,
    },
    /// A malformed line in a text file (list, CSV, calibration, catalog).
    #[error("{}:{line}: {msg}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number (0 when the whole file is at fault).
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// A PNG that cannot be decoded (truncated, corrupt, not a PNG).
    #[error("{}: cannot decode image: {msg}", path.display())]
    Decode {
        /// The image file.
        path: PathBuf,
        /// The decoder's message.
        msg: String,
    },
    /// A depth image that is not a 16-bit single-channel PNG.
    #[error(
        "{}: depth image must be a 16-bit single-channel PNG (TUM layout, metres * depth factor), found {found}",
        path.display()
    )]
    DepthFormat {
        /// The depth file.
        path: PathBuf,
        /// The pixel format found, e.g. "8-bit grey".
        found: String,
    },
    /// An image whose size differs from the sequence's camera or from its partner image.
    #[error("{}: image is {found_w}x{found_h}, expected {expected_w}x{expected_h} ({what})", path.display())]
    SizeMismatch {
        /// The image file.
        path: PathBuf,
        /// Width found.
        found_w: usize,
        /// Height found.
        found_h: usize,
        /// Width expected.
        expected_w: usize,
        /// Height expected.
        expected_h: usize,
        /// Where the expectation comes from.
        what: String,
    },
    /// A folder that is neither a TUM RGB-D nor an EuRoC sequence, or inconsistent data in it.
    #[error("{}: {msg}", path.display())]
    Invalid {
        /// The folder or file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
    /// The ground-truth file could not be read.
    #[error("{}: ground truth: {msg}", path.display())]
    GroundTruth {
        /// The ground-truth file.
        path: PathBuf,
        /// The reader's message.
        msg: String,
    },
    /// A sequence name the catalog does not know.
    #[error("unknown sequence `{name}`{}", suggest(suggestions))]
    UnknownSequence {
        /// The name asked for.
        name: String,
        /// The closest catalogued names (edit distance), best first.
        suggestions: Vec<String>,
    },
    /// A download that could not be done; `hint` says how to place the files by hand.
    #[error("cannot download {url}: {msg}\n{hint}")]
    Download {
        /// The URL.
        url: String,
        /// What failed (no network, HTTP status, short read...).
        msg: String,
        /// Where to put the files by hand.
        hint: String,
    },
    /// An output folder that exists and is not empty (a writer never overwrites).
    #[error("{}: the output folder exists and is not empty (remove it or choose another)", path.display())]
    OutputExists {
        /// The folder.
        path: PathBuf,
    },
    /// An image that cannot be encoded while writing a folder.
    #[error("{}: cannot encode image: {msg}", path.display())]
    Encode {
        /// The image file.
        path: PathBuf,
        /// The encoder's message.
        msg: String,
    },
    /// A synthetic sequence that cannot be generated as asked (frames beyond a recorded path).
    #[error(transparent)]
    Synth(#[from] synth::SynthError),
    /// An archive that cannot be unpacked.
    #[error("{}: cannot unpack: {msg}", path.display())]
    Archive {
        /// The archive file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
}

fn suggest(s: &[String]) -> String {
    if s.is_empty() {
        String::new()
    } else {
        format!("; did you mean {}?", s.join(", "))
    }
}

impl From<atomic_file::WriteError> for DatasetError {
    fn from(e: atomic_file::WriteError) -> Self {
        match e {
            atomic_file::WriteError::Io { path, cause } => DatasetError::io(path, cause),
            atomic_file::WriteError::Occupied { path } => DatasetError::OutputExists { path },
        }
    }
}

impl DatasetError {
    /// Wraps an I/O error with the path it happened on.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        DatasetError::Io {
            path: path.into(),
            source,
        }
    }

    /// A parse error at `line` of `path`.
    pub fn parse(path: impl Into<PathBuf>, line: usize, msg: impl Into<String>) -> Self {
        DatasetError::Parse {
            path: path.into(),
            line,
            msg: msg.into(),
        }
    }

    /// Inconsistent or unusable data in `path`.
    pub fn invalid(path: impl Into<PathBuf>, msg: impl Into<String>) -> Self {
        DatasetError::Invalid {
            path: path.into(),
            msg: msg.into(),
        }
    }
}
