//! Property tests of the EtherCAT codecs: round trips of frames, datagram headers, mailbox and
//! CoE headers and SII images, and arbitrary bytes never panic any decoder (the short in-CI
//! counterpart of the fuzz targets in `rl-drivers/fuzz`).

use proptest::prelude::*;
use rl_drivers::proto::ecat::coe::{self, CoeHeader, CoeService, SdoMessage};
use rl_drivers::proto::ecat::datagram::{DatagramHeader, HEADER_LEN};
use rl_drivers::proto::ecat::frame::{Frame, FrameBuilder, MAX_FRAME_LEN, MacAddr};
use rl_drivers::proto::ecat::mailbox::{MailboxHeader, MailboxType};
use rl_drivers::proto::ecat::sii::{
    CategoryType, General, MailboxWindow, Sii, SiiHeader, SiiWriter,
};

prop_compose! {
    fn header()(cmd in 0u8..=14, index in any::<u8>(), address in any::<u32>(), irq in any::<u16>(),
                circulating in any::<bool>()) -> DatagramHeader {
        DatagramHeader { cmd, index, address, len: 0, circulating, more_follows: false, irq }
    }
}

proptest! {
    #[test]
    fn datagram_headers_round_trip(h in header(), len in 0u16..0x800, more in any::<bool>()) {
        let h = DatagramHeader { len, more_follows: more, ..h };
        let mut b = [0u8; HEADER_LEN];
        h.encode(&mut b);
        prop_assert_eq!(DatagramHeader::decode(&b), Ok(h));
    }

    #[test]
    fn frames_round_trip(items in proptest::collection::vec((header(), proptest::collection::vec(any::<u8>(), 0..200)), 1..8),
                         wkc in any::<u16>()) {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let mut b = FrameBuilder::new(&mut buf, MacAddr::MASTER).unwrap();
        let mut pushed = Vec::new();
        for (h, data) in &items {
            if b.room() < data.len() {
                break;
            }
            let at = b.push(*h, data).unwrap();
            pushed.push((*h, data.clone(), at));
        }
        let n = b.finish();
        // A device would write working counters in place; put one into each.
        for (_, data, at) in &pushed {
            buf[at + data.len()..at + data.len() + 2].copy_from_slice(&wkc.to_le_bytes());
        }
        let f = Frame::decode(&buf[..n]).unwrap();
        let got: Vec<_> = f.datagrams().map(Result::unwrap).collect();
        prop_assert_eq!(got.len(), pushed.len());
        for (k, (d, (h, data, _))) in got.iter().zip(&pushed).enumerate() {
            prop_assert_eq!(d.header.cmd, h.cmd);
            prop_assert_eq!(d.header.index, h.index);
            prop_assert_eq!(d.header.address, h.address);
            prop_assert_eq!(d.header.irq, h.irq);
            prop_assert_eq!(d.header.more_follows, k + 1 < pushed.len());
            prop_assert_eq!(d.data, &data[..]);
            prop_assert_eq!(d.wkc, wkc);
        }
    }

    #[test]
    fn mailbox_and_coe_headers_round_trip(length in any::<u16>(), address in any::<u16>(), channel in 0u8..64,
                                           priority in 0u8..4, kind in 0u8..16, counter in 0u8..8,
                                           number in 0u16..512, service in 0u8..16) {
        let h = MailboxHeader { length, address, channel, priority, kind: MailboxType::from_code(kind), counter };
        prop_assert_eq!(MailboxHeader::decode(&h.encode()), Ok(h));
        let c = CoeHeader { number, service: CoeService::from_code(service) };
        prop_assert_eq!(CoeHeader::decode(c.encode()), c);
    }

    #[test]
    fn sii_images_round_trip(vendor in any::<u32>(), product in any::<u32>(),
                             names in proptest::collection::vec("[ -~]{0,40}", 1..6),
                             coe in any::<u8>()) {
        let mut buf = [0u8; 4096];
        let header = SiiHeader {
            vendor_id: vendor,
            product_code: product,
            mailbox_out: MailboxWindow { offset: 0x1000, size: 128 },
            ..SiiHeader::default()
        };
        let mut w = SiiWriter::new(&mut buf, &header).unwrap();
        let refs: Vec<&[u8]> = names.iter().map(|s| s.as_bytes()).collect();
        w.strings(&refs).unwrap();
        let g = General { name_index: names.len() as u8, coe_details: coe, ..General::default() };
        w.category(CategoryType::General, 32, |d| d.copy_from_slice(&g.encode(0))).unwrap();
        let n = w.finish();
        let sii = Sii::new(&buf[..n]);
        prop_assert_eq!(sii.vendor_id(), Ok(vendor));
        prop_assert_eq!(sii.product_code(), Ok(product));
        prop_assert!(sii.checksum_ok().unwrap());
        prop_assert_eq!(sii.name(), Ok(names.last().unwrap().as_bytes()));
        for (k, s) in names.iter().enumerate() {
            prop_assert_eq!(sii.string(k as u8 + 1), Ok(s.as_bytes()));
        }
        prop_assert_eq!(sii.general().unwrap().unwrap().coe_details, coe);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..1600)) {
        if let Ok(f) = Frame::decode(&bytes) {
            for d in f.datagrams() {
                let _ = d.unwrap().header.command();
            }
        }
        let _ = MailboxHeader::split(&bytes);
        if let Ok(m) = SdoMessage::parse(&bytes) {
            let _ = m.request();
            let _ = m.response();
            let _ = m.segment_data(coe::sdo_part(&bytes));
            let _ = m.normal_data(usize::from(bytes.first().copied().unwrap_or(0)));
        }
        let sii = Sii::new(&bytes);
        let _ = (sii.vendor_id(), sii.name(), sii.general(), sii.fmmu_usage(), sii.checksum_ok());
        for c in sii.categories() { let _ = c; }
        for p in sii.pdos(true).chain(sii.pdos(false)).flatten() {
            let _ = p.bits();
        }
        if let Ok(s) = sii.sync_managers() { let _ = s.count(); }
        if let Ok(m) = sii.dc_modes() { let _ = m.count(); }
        for k in 0..=255u8 { let _ = sii.string(k); }
    }

    #[test]
    fn frames_with_an_ethercat_header_never_panic(tail in proptest::collection::vec(any::<u8>(), 0..300)) {
        let mut bytes = vec![0xFF; 12];
        bytes.extend_from_slice(&[0x88, 0xA4]);
        bytes.extend_from_slice(&tail);
        if let Ok(f) = Frame::decode(&bytes) {
            prop_assert!(f.datagrams().all(|d| d.is_ok()));
        }
    }
}
