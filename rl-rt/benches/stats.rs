//! Cost of what the loop does every cycle besides sleeping: a histogram sample, a queue
//! round trip, a mailbox publish/read. (Jitter itself is measured by `rl jitter` and
//! `scripts/jitter-vs-cyclictest`, not here.)

#![allow(missing_docs)] // criterion_group! generates an undocumented pub fn

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rl_rt::Histogram;
use rl_rt::exchange::{mailbox, queue};

fn per_cycle(c: &mut Criterion) {
    let mut h = Histogram::new(10_000);
    let mut x = 0u64;
    c.bench_function("histogram_record", |b| {
        b.iter(|| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            h.record(black_box(x >> 45));
        })
    });
    c.bench_function("histogram_summary_10k_bins", |b| {
        b.iter(|| black_box(h.summary()))
    });
    let (mut tx, mut rx) = queue::<[f64; 8]>(64);
    c.bench_function("queue_send_recv", |b| {
        b.iter(|| {
            let _ = tx.try_send(black_box([1.0; 8]));
            black_box(rx.try_recv())
        })
    });
    let (mut w, mut r) = mailbox([0.0f64; 8]);
    c.bench_function("mailbox_publish_read", |b| {
        b.iter(|| {
            w.publish(black_box([2.0; 8]));
            black_box(r.read()[0])
        })
    });
}

criterion_group!(benches, per_cycle);
criterion_main!(benches);
