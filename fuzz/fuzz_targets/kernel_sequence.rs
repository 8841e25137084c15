//! The kernel over arbitrary sequences of (frame, request, time),
//! structure-aware ([`limb_fuzz::session`]): every step is checked against
//! the safety properties of `limb_verification::checks`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use limb_fuzz::session::{run, Session};

fuzz_target!(|session: Session| run(&session));
