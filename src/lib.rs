//! crosscheck: a verification harness for explicit dynamics.
//!
//! Data flows cases → scene → engines → comparison → report:
//! [`case`] reads `cases/*.toml`, [`scene`] validates them into the one type engines share,
//! [`engines`] turn a scene into time histories, and [`report`] writes them out.

pub mod case;
pub mod comparison;
pub mod engines;
pub mod report;
pub mod run;
pub mod scene;
