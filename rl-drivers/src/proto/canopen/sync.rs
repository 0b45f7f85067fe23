//! SYNC (COB-ID 0x080): no data, or one counter byte 1..=240 when the producer's synchronous
//! counter overflow value (0x1019) is set (CiA 301 §7.2.5).

use super::cob::SYNC;
use crate::proto::can::Frame;

/// A SYNC frame, with the optional counter.
pub fn frame(counter: Option<u8>) -> Frame {
    let f = match counter {
        Some(c) => Frame::standard(SYNC, &[c]),
        None => Frame::standard(SYNC, &[]),
    };
    f.unwrap_or_else(super::nmt::no_frame)
}

/// A SYNC's counter from its data: `Ok(None)` without one, `Err` for a malformed length.
pub fn decode(data: &[u8]) -> Result<Option<u8>, usize> {
    match data {
        [] => Ok(None),
        [c] => Ok(Some(*c)),
        _ => Err(data.len()),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn sync_is_empty_or_carries_a_counter() {
        assert!(super::frame(None).bytes().is_empty());
        assert_eq!(super::frame(Some(7)).bytes(), &[7]);
        assert_eq!(super::decode(&[]), Ok(None));
        assert_eq!(super::decode(&[1, 2]), Err(2));
    }
}
