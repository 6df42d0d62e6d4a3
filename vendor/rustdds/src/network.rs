pub mod constant;
pub mod scope; // cstep patch
pub mod udp_listener;
pub mod udp_sender;
pub mod util;
