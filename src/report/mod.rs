//! Writing results: the files other tools read (see the output contract in the spec).
//!
//! [`data`] holds the time histories, one CSV per case and engine.

pub mod data;
