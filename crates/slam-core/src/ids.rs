//! Typed arena indices: a `KeyFrameId` can never be used where a `MapPointId` is expected.

use std::fmt;

/// Index of a keyframe in [`crate::data::Map`]; ids grow with insertion order and are never
/// reused, so id order is creation order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct KeyFrameId(pub u32);

/// Index of a map point in [`crate::data::Map`]; ids grow with creation order, never reused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MapPointId(pub u32);

impl KeyFrameId {
    /// Position in the arena.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl MapPointId {
    /// Position in the arena.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl fmt::Display for KeyFrameId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "KF{}", self.0)
    }
}

impl fmt::Display for MapPointId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "MP{}", self.0)
    }
}
