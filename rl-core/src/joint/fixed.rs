//! Fixed joint: no motion. Models merge fixed joints into the parent body when they are built
//! (the child's inertia and frames move to the parent), so no algorithm ever visits one.

use crate::spatial::PlueckerTransform;

/// A rigid connection with the given pose of the child in the parent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fixed {
    /// Pose of the child frame in the parent frame.
    pub placement: PlueckerTransform,
}
