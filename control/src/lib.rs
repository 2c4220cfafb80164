//! The hardware-independent heart of the hexapod firmware (work in progress).
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

pub mod number;
pub mod protocol;
pub mod motion;
