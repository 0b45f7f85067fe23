//! Codec throughput: H7 packet encode/decode, Coach line encode/parse and the EtherCAT cyclic
//! frame of 6 CiA 402 drives (one control cycle's worth of wire work each). Run with `cargo
//! bench -p rl-drivers`.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rl_drivers::proto::coach::{Message, Values};
use rl_drivers::proto::h7::{Command, Data, MxtType, PACKET_LEN, Packet};

fn h7(c: &mut Criterion) {
    let p = Packet {
        command: Command::Move,
        send_type: MxtType::Joint,
        recv_type: MxtType::JointFeedback,
        dat: Data::from_joints(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.0, 0.0]),
        recv_type1: MxtType::PoseFeedback,
        recv_type2: MxtType::PulseFeedback,
        recv_type3: MxtType::CurrentFeedback,
        c_count: 42,
        ..Packet::default()
    };
    let bytes = p.to_bytes();
    c.bench_function("h7 encode", |b| {
        let mut out = [0u8; PACKET_LEN];
        b.iter(|| black_box(&p).encode(black_box(&mut out)))
    });
    c.bench_function("h7 decode", |b| {
        b.iter(|| Packet::decode(black_box(&bytes)))
    });
}

fn coach(c: &mut Criterion) {
    let values = Values::from_slice(&[0.123456, -1.5, 2.25e-5, 3.0, -0.75, 1e6]).unwrap();
    let m = Message::JointPosition { model: 0, values };
    let mut buf = [0u8; 512];
    let n = m.encode(&mut buf).unwrap();
    let line = buf[..n - 1].to_vec();
    c.bench_function("coach encode 6 joints", |b| {
        let mut out = [0u8; 512];
        b.iter(|| black_box(&m).encode(black_box(&mut out)))
    });
    c.bench_function("coach parse 6 joints", |b| {
        b.iter(|| Message::parse(black_box(&line)))
    });
}

/// The cyclic frame of `EthercatDrives` with 6 drives: LRW of 6 × (15 + 15) bytes, FRMW of the
/// reference clock, BRD of AL status.
fn ecat(c: &mut Criterion) {
    use rl_drivers::proto::ecat::command::Command;
    use rl_drivers::proto::ecat::datagram::{DatagramHeader, physical};
    use rl_drivers::proto::ecat::frame::{Frame, FrameBuilder, MAX_FRAME_LEN, MacAddr};
    let image = [0x5Au8; 180];
    let encode = |buf: &mut [u8]| {
        let mut b = FrameBuilder::new(buf, MacAddr::MASTER).unwrap();
        b.push(DatagramHeader::new(Command::Lrw, 0, 0), &image)
            .unwrap();
        b.push_zeroed(
            DatagramHeader::new(Command::Frmw, physical(0x1001, 0x0910), 0),
            8,
        )
        .unwrap();
        b.push_zeroed(DatagramHeader::new(Command::Brd, physical(0, 0x0130), 0), 2)
            .unwrap();
        b.finish()
    };
    let mut frame = [0u8; MAX_FRAME_LEN];
    let n = encode(&mut frame);
    c.bench_function("ecat encode cyclic frame 6 drives", |b| {
        let mut buf = [0u8; MAX_FRAME_LEN];
        b.iter(|| encode(black_box(&mut buf)))
    });
    c.bench_function("ecat decode cyclic frame 6 drives", |b| {
        b.iter(|| {
            let f = Frame::decode(black_box(&frame[..n])).unwrap();
            f.datagrams().map(|d| d.unwrap().wkc).sum::<u16>()
        })
    });
}

criterion_group!(benches, h7, coach, ecat);
criterion_main!(benches);
