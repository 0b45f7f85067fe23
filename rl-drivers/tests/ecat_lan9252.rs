//! Our fake ESC against real hardware: SOEM's requests from `soem-single-lan9252.pcapng`
//! (tests/data/ecat; Microchip LAN9252 evaluation board) are replayed, with the capture's own
//! time stamps as the fake's clock, into a fake device configured from the same SII — the SII
//! words the real device returned in that capture — and the objects its CoE server answered
//! (0x1C00, 0x1C12, 0x1C13 and the PDO mappings, taken from the capture's SDO responses,
//! because SOEM read them by SDO, not from the SII). Every datagram our fake returns must match
//! the real device's reply: command, index, addresses, length, IRQ, working counter and data.
//!
//! Two kinds of replies depend on the time the device's firmware takes and are compared by what
//! cannot depend on it:
//! - polls (the same read repeated while waiting: AL status, sync manager status, SII status):
//!   each of our answers is one the real device gave during that poll, and the answer that ended
//!   the poll (SOEM stopped polling on it) is the real one exactly;
//! - distributed-clock time registers (0x0900-0x091F): working counter and length only.
//!
//! The fake's firmware latency is 18 ms, what the capture shows for the LAN9252's INIT → PRE-OP
//! transition (AL status still INIT 16.5 ms after the request, PRE-OP 18.5 ms after it); with it the AL control handshake refuses SOEM's repeated INIT requests exactly as
//! the real device did (frames 6 and 30). The bytes of a mailbox buffer after the message are
//! whatever the RAM held (the real device returns stale bytes there) and are not compared.

mod support;

use std::collections::BTreeMap;

use rl_drivers::fake::ecat_segment::Segment;
use rl_drivers::fake::ecat_segment::description::{DeviceDescription, Profile};
use rl_drivers::fake::ecat_segment::dictionary::Access;
use rl_drivers::fake::ecat_segment::esc::EscIdentity;
use rl_drivers::proto::canopen::object::DataType;
use rl_drivers::proto::canopen::sdo::{Request, Response};
use rl_drivers::proto::ecat::coe::{self, SdoMessage};
use rl_drivers::proto::ecat::datagram::Datagram;
use rl_drivers::proto::ecat::frame::Frame;
use rl_drivers::proto::ecat::mailbox::MailboxHeader;
use rl_drivers::proto::ecat::sii::Sii;

struct Exchange {
    time_ns: u64,
    request: Vec<u8>,
    reply: Vec<u8>,
}

fn exchanges() -> Vec<Exchange> {
    let packets = support::read_pcapng(&support::capture_dir().join("soem-single-lan9252.pcapng"));
    let mut out = Vec::new();
    let mut pending: Option<(u64, Vec<u8>)> = None;
    for p in packets {
        let Ok(f) = Frame::decode(&p.data) else {
            continue;
        };
        if f.ethernet.source.is_forwarded() {
            let (time_ns, request) = pending.take().expect("a reply follows a request");
            out.push(Exchange {
                time_ns,
                request,
                reply: p.data.clone(),
            });
        } else {
            assert!(pending.is_none(), "two requests in a row");
            pending = Some((p.time.as_nanos() as u64, p.data.clone()));
        }
    }
    out
}

fn datagrams(frame: &[u8]) -> Vec<Datagram<'_>> {
    Frame::decode(frame)
        .unwrap()
        .datagrams()
        .map(Result::unwrap)
        .collect()
}

/// The SII words and the CoE objects the real device returned.
fn from_capture(ex: &[Exchange]) -> (Vec<u8>, BTreeMap<u16, Vec<u8>>) {
    // Words SOEM did not read: the configuration area as the registers show it was loaded
    // (alias 0x0012 = 0 in frame 44), erased cells (0xFF) beyond.
    let mut sii = vec![0xFFu8; 1024];
    sii[..0x80].fill(0);
    let mut word = None;
    let mut upload = None;
    let mut objects = BTreeMap::new();
    for e in ex {
        let (q, r) = (&datagrams(&e.request)[0], &datagrams(&e.reply)[0]);
        match (q.header.cmd, q.header.ado()) {
            (5, 0x0502) if q.data.len() == 6 && q.data[1] == 0x01 => {
                word = Some(u32::from_le_bytes(q.data[2..6].try_into().unwrap()) as usize);
            }
            (4, 0x0508) => {
                if let Some(w) = word.take() {
                    sii[2 * w..2 * w + r.data.len()].copy_from_slice(r.data);
                }
            }
            (5, 0x1000) => {
                let (_, body) = MailboxHeader::split(q.data).unwrap();
                let m = SdoMessage::parse(body).unwrap();
                if let (Ok(Request::UploadInitiate { address }), true) =
                    (m.request(), m.complete_access())
                {
                    upload = Some(address.index);
                }
            }
            (4, 0x1080) if r.wkc == 1 => {
                let (_, body) = MailboxHeader::split(r.data).unwrap();
                let m = SdoMessage::parse(body).unwrap();
                let value = match m.response().unwrap() {
                    Response::UploadExpedited { data, .. } => data.as_slice().to_vec(),
                    Response::UploadInitiate { size, .. } => {
                        m.normal_data(size.unwrap() as usize).to_vec()
                    }
                    other => panic!("unexpected {other:?}"),
                };
                objects.insert(upload.take().unwrap(), value);
            }
            _ => {}
        }
    }
    (sii, objects)
}

fn lan9252(sii: Vec<u8>, objects: &BTreeMap<u16, Vec<u8>>) -> DeviceDescription {
    let s = Sii::new(&sii);
    let mut d = DeviceDescription::coupler(0);
    d.esc = EscIdentity::LAN9252;
    d.name = String::from_utf8_lossy(s.string(1).unwrap()).into_owned();
    d.mailbox_out = s.mailbox_out().unwrap();
    d.mailbox_in = s.mailbox_in().unwrap();
    d.profile = Profile::Plain;
    d.firmware_latency_ns = 18_000_000;
    for (&index, value) in objects {
        // Complete access: sub-index 0 as 16 bits, then equal-sized sub-indices.
        let count = usize::from(value[0]);
        let each = (value.len() - 2) / count.max(1);
        let t = match each {
            1 => DataType::Unsigned8,
            2 => DataType::Unsigned16,
            _ => DataType::Unsigned32,
        };
        for k in 0..count {
            let v = value[2 + k * each..2 + (k + 1) * each].to_vec();
            d.extra_objects
                .push((index, k as u8 + 1, t, Access::RwPreOp, false, v));
        }
    }
    d.sii_image = Some(sii);
    d
}

fn is_time_register(ado: u16) -> bool {
    (0x0900..0x0920).contains(&ado)
}

fn is_poll(ado: u16) -> bool {
    matches!(ado, 0x0130 | 0x0502 | 0x0805 | 0x080D)
}

#[test]
fn our_fake_answers_soem_as_the_lan9252_did() {
    let ex = exchanges();
    assert_eq!(ex.len(), 499, "request/reply pairs in the capture");
    let (sii, objects) = from_capture(&ex);
    assert_eq!(
        objects.keys().copied().collect::<Vec<_>>(),
        [0x1600 + 1, 0x1A00, 0x1A02, 0x1C00, 0x1C12, 0x1C13],
        "the objects SOEM read"
    );
    let d = lan9252(sii, &objects);
    assert_eq!(d.name, "LAN9252-EVB-HBI");
    let mut seg = Segment::new(&[d], 0, 1, &[]);
    let t0 = ex[0].time_ns;
    // Poll runs: consecutive frames with the same single read. For each frame: the values the
    // real device returned during its run, and whether it ended the run.
    let key = |e: &Exchange| {
        let q = datagrams(&e.request)[0];
        (q.header.cmd, q.header.address, q.header.len)
    };
    let mut run_values: Vec<Vec<Vec<u8>>> = vec![Vec::new(); ex.len()];
    let mut run_end = vec![false; ex.len()];
    let mut k = 0;
    while k < ex.len() {
        let mut end = k;
        while end + 1 < ex.len() && key(&ex[end + 1]) == key(&ex[k]) {
            end += 1;
        }
        let values: Vec<Vec<u8>> = (k..=end)
            .map(|i| datagrams(&ex[i].reply)[0].data.to_vec())
            .collect();
        for v in run_values.iter_mut().take(end + 1).skip(k) {
            *v = values.clone();
        }
        run_end[end] = true;
        k = end + 1;
    }
    let (mut exact, mut sooner, mut timed) = (0, 0, 0);
    // The firmware runs after every frame and every 250 µs in between, as on the fake's thread.
    let tick = 250_000;
    let mut next_tick = 1_000_000_000;
    for (n, e) in ex.iter().enumerate() {
        let t = e.time_ns - t0 + 1_000_000_000;
        while next_tick < t {
            seg.pdi_step(next_tick);
            next_tick += tick;
        }
        let mut frame = e.request.clone();
        assert!(
            seg.process(&mut frame, t),
            "exchange {n}: the fake returns the frame"
        );
        seg.pdi_step(t);
        let (ours, real) = (datagrams(&frame), datagrams(&e.reply));
        assert_eq!(ours.len(), real.len());
        for (o, r) in ours.iter().zip(&real) {
            let at = format!("exchange {n} (capture frame {}), {:?}", 2 * n + 1, r.header);
            assert_eq!(o.header, r.header, "{at}: header (ADP increment, IRQ)");
            assert_eq!(o.wkc, r.wkc, "{at}: working counter");
            let ado = r.header.ado();
            if is_time_register(ado) && r.header.cmd != 8 {
                timed += 1;
                continue;
            }
            if ado == 0x1080 && r.wkc == 1 {
                // A mailbox message: compare the message, not the stale RAM after it.
                let len = 6 + usize::from(u16::from_le_bytes([r.data[0], r.data[1]]));
                assert_eq!(&o.data[..len], &r.data[..len], "{at}: mailbox message");
                exact += 1;
                continue;
            }
            if o.data == r.data {
                exact += 1;
            } else if is_poll(ado) && !run_end[n] && run_values[n].iter().any(|v| v == o.data) {
                // Within a poll, a value the device showed during it (ours sooner or later by
                // the firmware's timing); the poll's last answer must match exactly.
                sooner += 1;
            } else {
                panic!(
                    "{at}: data {:02x?}, the LAN9252 returned {:02x?}",
                    o.data, r.data
                );
            }
        }
    }
    println!(
        "{exact} datagrams equal the LAN9252's, {sooner} poll answers at another moment of the same poll, {timed} time registers"
    );
    assert_eq!(exact + sooner + timed, 499, "every datagram compared");
    let s = &seg.status()[0];
    assert_eq!(
        s.state,
        rl_drivers::proto::ecat::al::AlState::SafeOp,
        "ends in SAFE-OP as the capture does"
    );
    let _ = coe::HEADER_LEN;
}
