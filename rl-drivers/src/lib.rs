//! Cyclic devices (open, start, step, stop, close), protocol codecs and loopback fake robots.
//!
//! Not built yet: see issue 6. This crate is a placeholder so the workspace builds.
#![cfg_attr(not(feature = "std"), no_std)]
