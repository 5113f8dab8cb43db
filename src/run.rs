//! Drives a scene from its first step to its last frame.
