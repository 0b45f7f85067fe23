//! CAN and CANopen: codec cost per frame (SocketCAN layout, cannelloni, candump, SDO, PDO
//! packing) and one `Cia402::step()` with six axes against the fake drives over cannelloni UDP
//! on loopback (SYNC + 6 RPDOs out as one datagram, 6 TPDOs back). Run with
//! `cargo bench -p rl-drivers --bench can`.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rl_drivers::canopen::{Cia402, Cia402Config};
use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config};
use rl_drivers::proto::can::candump::{self, Timestamp};
use rl_drivers::proto::can::cannelloni::{self, DatagramWriter};
use rl_drivers::proto::can::{Frame, IdOrder};
use rl_drivers::proto::canopen::pdo::{Entry, Mapping};
use rl_drivers::proto::canopen::sdo::{Address, Request, Response};
use rl_drivers::transport::can::CanAddress;
use rl_drivers::{CyclicDevice, Device, JointPositionActuator};

fn cycle_frames() -> Vec<Frame> {
    let mut frames = vec![Frame::standard(0x080, &[]).unwrap()];
    for n in 1..=6u16 {
        frames
            .push(Frame::standard(0x200 + n, &[0x0F, 0, 0x10, 0x20, 0x30, 0x40, 0x05, 0]).unwrap());
    }
    frames
}

fn codec(c: &mut Criterion) {
    let f = Frame::standard(0x181, &[0x27, 0x16, 0x10, 0x20, 0x30, 0x40, 0x05, 0]).unwrap();
    let mut g = c.benchmark_group("can codec");
    g.throughput(Throughput::Elements(1));
    g.bench_function("socketcan can_frame write", |b| {
        let mut out = [0u8; 16];
        b.iter(|| black_box(&f).write_socketcan(black_box(&mut out), IdOrder::Host))
    });
    let mut bytes = [0u8; 16];
    f.write_socketcan(&mut bytes, IdOrder::Host).unwrap();
    g.bench_function("socketcan can_frame read", |b| {
        b.iter(|| Frame::read_socketcan(black_box(&bytes), IdOrder::Host))
    });
    g.bench_function("candump line write", |b| {
        let mut s = String::with_capacity(64);
        b.iter(|| {
            s.clear();
            candump::write_line(
                &mut s,
                Timestamp {
                    secs: 1_764_600_000,
                    micros: 123_456,
                },
                "can0",
                black_box(&f),
            )
        })
    });
    g.bench_function("candump line parse", |b| {
        b.iter(|| candump::parse_line(black_box("(1764600000.123456) can0 181#2716102030400500")))
    });
    let r = Request::UploadInitiate {
        address: Address::new(0x6064, 0),
    };
    g.bench_function("sdo request encode", |b| b.iter(|| black_box(&r).encode()));
    let resp = Response::UploadExpedited {
        address: Address::new(0x6064, 0),
        data: rl_drivers::proto::canopen::sdo::Chunk::new(&[1, 2, 3, 4]).unwrap(),
    }
    .encode();
    g.bench_function("sdo response decode", |b| {
        b.iter(|| Response::decode(black_box(&resp)))
    });
    let m = Mapping::new(&[
        Entry::new(0x6041, 0, 16),
        Entry::new(0x6064, 0, 32),
        Entry::new(0x6077, 0, 16),
    ])
    .unwrap();
    let (sw, pos, tq) = (
        m.locate(0x6041, 0).unwrap(),
        m.locate(0x6064, 0).unwrap(),
        m.locate(0x6077, 0).unwrap(),
    );
    g.bench_function("tpdo unpack (statusword, position, torque)", |b| {
        b.iter(|| {
            let d = black_box(f.bytes());
            (sw.get_unsigned(d), pos.get_signed(d), tq.get_signed(d))
        })
    });
    g.finish();

    let frames = cycle_frames();
    let mut g = c.benchmark_group("cannelloni cycle (SYNC + 6 RPDOs)");
    g.throughput(Throughput::Elements(frames.len() as u64));
    g.bench_function("datagram encode", |b| {
        let mut buf = [0u8; 256];
        b.iter(|| {
            let mut w = DatagramWriter::new(&mut buf, 1).unwrap();
            for f in black_box(&frames) {
                w.push(f).unwrap();
            }
            w.as_bytes().len()
        })
    });
    let mut buf = [0u8; 256];
    let mut w = DatagramWriter::new(&mut buf, 1).unwrap();
    for f in &frames {
        w.push(f).unwrap();
    }
    let datagram = w.as_bytes().to_vec();
    g.bench_function("datagram decode", |b| {
        b.iter(|| {
            let (_, it) = cannelloni::read_datagram(black_box(&datagram)).unwrap();
            it.filter(|f| f.is_ok()).count()
        })
    });
    g.finish();
}

fn step(c: &mut Criterion) {
    let nodes = [1, 2, 3, 4, 5, 6];
    for delay_us in [0u64, 100] {
        let mut fc = FakeCia402Config::new(&nodes).unwrap();
        fc.tpdo_delay = Duration::from_micros(delay_us);
        fc.sync_loss_periods = 1000; // criterion pauses between phases
        let fake = FakeCia402::serve(
            fc,
            &CanAddress::parse("cannelloni+udp://127.0.0.1:0").unwrap(),
        )
        .unwrap();
        let bus =
            CanAddress::parse(&format!("cannelloni+udp://{}", fake.local_addr().unwrap())).unwrap();
        let mut config = Cia402Config::new(bus, &nodes);
        config.sdo_timeout = Duration::from_millis(200);
        config.max_consecutive_failures = u32::MAX;
        let mut dev = Cia402::new(config).unwrap();
        dev.open().unwrap();
        dev.start().unwrap();
        let mut k = 0.0;
        c.bench_function(
            &format!("cia402 step, 6 axes, cannelloni udp loopback, TPDO delay {delay_us} µs"),
            |b| {
                b.iter(|| {
                    k += 1e-6;
                    dev.set_joint_position(&[k; 6]).unwrap();
                    let _ = dev.step();
                })
            },
        );
        let lost = dev.counters().tpdos_lost;
        println!("  (TPDOs lost during the benchmark: {lost})");
        dev.stop().unwrap();
    }
}

criterion_group!(benches, codec, step);
criterion_main!(benches);
