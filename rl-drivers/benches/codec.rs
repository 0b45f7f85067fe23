//! Codec throughput: H7 packet encode/decode and Coach line encode/parse (one control cycle's
//! worth of wire work each). Run with `cargo bench -p rl-drivers`.
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

criterion_group!(benches, h7, coach);
criterion_main!(benches);
