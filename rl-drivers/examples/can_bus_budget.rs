//! The bus budget of a CiA 402 cycle: bits and µs per cycle for 1–8 axes (SYNC, one 8-byte
//! RPDO and one 8-byte TPDO per axis), nominal and with worst-case bit stuffing, and the
//! shortest cycle (highest rate) the rule of `rl_drivers::canopen::BusLoad` accepts, at
//! 1 Mbit/s and 500 kbit/s. Run with `cargo run -p rl-drivers --example can_bus_budget`.

use rl_drivers::canopen::BusLoad;

fn main() {
    for bitrate in [1_000_000u32, 500_000] {
        println!("{} kbit/s", bitrate / 1000);
        println!(
            "| axes | frames | bits | bits (worst stuffing) | µs | µs (worst) | shortest cycle µs | highest rate Hz |"
        );
        println!("|---|---|---|---|---|---|---|---|");
        for axes in 1..=8 {
            let l = BusLoad::symmetric(axes, bitrate);
            let min = l.min_period().as_secs_f64();
            println!(
                "| {axes} | {} | {} | {} | {:.0} | {:.0} | {:.0} | {:.0} |",
                l.frames,
                l.bits,
                l.bits_worst,
                l.time_us(),
                l.time_worst_us(),
                min * 1e6,
                1.0 / min
            );
        }
        println!();
    }
}
