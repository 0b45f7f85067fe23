//! Any bytes: the mailbox header, the CoE header and the SDO message after it decode or are
//! refused, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::ecat::coe::{self, SdoMessage};
use rl_drivers::proto::ecat::mailbox::{MailboxErrorCode, MailboxHeader};

fuzz_target!(|data: &[u8]| {
    if let Ok((h, body)) = MailboxHeader::split(data) {
        assert_eq!(MailboxHeader::decode(&h.encode()), Ok(h));
        let _ = MailboxErrorCode::from_reply(body);
        if let Ok(m) = SdoMessage::parse(body) {
            let _ = (m.request(), m.response(), m.complete_access());
            let _ = m.segment_data(coe::sdo_part(body));
            let _ = m.normal_data(body.len());
        }
    }
});
