//! ROS 2's wire format over Zenoh, as rmw_zenoh (ROS 2 Jazzy's Tier-1 Zenoh middleware) writes
//! it: CDR payloads ([`cdr`]), the messages a cell exchanges ([`msg`]), their RIHS01 type hashes
//! ([`type_hash`]), key expressions and liveliness tokens ([`names`]) and the per-sample
//! attachment ([`attachment`]).

pub mod attachment;
pub mod cdr;
pub mod msg;
pub mod names;
pub mod type_hash;
