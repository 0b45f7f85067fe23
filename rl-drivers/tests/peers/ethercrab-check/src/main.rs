//! ethercrab against a segment: scan, distributed clocks with SYNC0, PRE-OP → SAFE-OP → OP,
//! process data with the working counter checked, CiA 402 drives enabled (shutdown, switch on,
//! enable operation) and moved in CSP through the default PDO mapping of our fake drive
//! (controlword, target position, …; statusword, position actual, …).
//!
//! Usage: ethercrab-check IFNAME CYCLES. Prints `key=value` lines; exits non-zero on an error.

use std::time::{Duration, Instant};

use ethercrab::std::{ethercat_now, tx_rx_task};
use ethercrab::subdevice_group::DcConfiguration;
use ethercrab::{DcSync, MainDevice, MainDeviceConfig, PduStorage, Timeouts};

const MAX_SUBDEVICES: usize = 16;
const MAX_PDU_DATA: usize = PduStorage::element_size(1100);
const MAX_FRAMES: usize = 16;
const PDI_LEN: usize = 256;
const CYCLE: Duration = Duration::from_millis(1);

static PDU_STORAGE: PduStorage<MAX_FRAMES, MAX_PDU_DATA> = PduStorage::new();

fn main() {
    let mut args = std::env::args().skip(1);
    let interface = args.next().expect("interface");
    let cycles: usize = args.next().map_or(500, |c| c.parse().expect("cycles"));
    let (tx, rx, pdu_loop) = PDU_STORAGE.try_split().expect("split once");
    let maindevice = MainDevice::new(
        pdu_loop,
        Timeouts {
            wait_loop_delay: Duration::from_millis(1),
            mailbox_response: Duration::from_millis(1000),
            state_transition: Duration::from_secs(5),
            eeprom: Duration::from_millis(100),
            pdu: Duration::from_millis(100),
            ..Timeouts::default()
        },
        MainDeviceConfig {
            dc_static_sync_iterations: 1000,
            ..MainDeviceConfig::default()
        },
    );
    let task = tx_rx_task(&interface, tx, rx).expect("raw socket");
    std::thread::spawn(move || smol::block_on(task));
    if let Err(e) = smol::block_on(run(&maindevice, cycles)) {
        println!("error={e:?}");
        std::process::exit(1);
    }
}

async fn run(maindevice: &MainDevice<'_>, cycles: usize) -> Result<(), ethercrab::error::Error> {
    let mut group = maindevice
        .init_single_group::<MAX_SUBDEVICES, PDI_LEN>(ethercat_now)
        .await?;
    println!("found={}", group.len());
    for mut s in group.iter_mut(maindevice) {
        let id = s.identity();
        println!(
            "device={:#06x} name={} vendor={} product={} revision={} serial={} dc={:?}",
            s.configured_address(),
            s.name(),
            id.vendor_id,
            id.product_id,
            id.revision,
            id.serial,
            s.dc_support()
        );
        s.set_dc_sync(DcSync::Sync0);
    }
    let group = group.into_pre_op_pdi(maindevice).await?;
    for _ in 0..200 {
        group.tx_rx_sync_system_time(maindevice).await?;
    }
    let group = group
        .configure_dc_sync(
            maindevice,
            DcConfiguration {
                start_delay: Duration::from_millis(100),
                sync0_period: CYCLE,
                sync0_shift: Duration::ZERO,
            },
        )
        .await?;
    let group = group.into_safe_op(maindevice).await?;
    println!("safeop=true");
    let group = group.request_into_op(maindevice).await?;
    let deadline = Instant::now() + Duration::from_secs(5);
    loop {
        let r = group.tx_rx_dc(maindevice).await?;
        if r.all_op() {
            break;
        }
        if Instant::now() > deadline {
            println!("op=false");
            return Ok(());
        }
        smol::Timer::after(CYCLE).await;
    }
    println!("op=true");
    for s in group.iter(maindevice) {
        let io = s.io_raw();
        println!("sizes={},{}", io.outputs().len(), io.inputs().len());
    }
    let expected = 3 * group.len() as u16;
    let mut start = Vec::new();
    for s in group.iter(maindevice) {
        let i = s.inputs_raw();
        start.push(i32::from_le_bytes([i[2], i[3], i[4], i[5]]));
    }
    let mut bad = 0;
    let mut next = Instant::now();
    for k in 0..cycles {
        for (n, s) in group.iter(maindevice).enumerate() {
            let cw: u16 = if k < 20 { 0x06 } else if k < 40 { 0x07 } else { 0x0F };
            let target = if k > 60 { start[n] + (k as i32 - 60) * 200 } else { start[n] };
            let mut o = s.outputs_raw_mut();
            o[0..2].copy_from_slice(&cw.to_le_bytes());
            o[2..6].copy_from_slice(&target.to_le_bytes());
            o[14] = 8; // CSP
        }
        let r = group.tx_rx_dc(maindevice).await?;
        if r.working_counter != expected {
            bad += 1;
        }
        next += CYCLE;
        smol::Timer::at(next).await;
    }
    println!("expected_wkc={expected}");
    println!("wkc_errors={bad}");
    for (n, s) in group.iter(maindevice).enumerate() {
        let i = s.inputs_raw();
        let sw = u16::from_le_bytes([i[0], i[1]]);
        let pos = i32::from_le_bytes([i[2], i[3], i[4], i[5]]);
        println!("drive={n} statusword={sw:#06x} moved={}", pos - start[n]);
    }
    let group = group.into_safe_op(maindevice).await?;
    let group = group.into_pre_op(maindevice).await?;
    let _ = group.into_init(maindevice).await?;
    println!("done=true");
    Ok(())
}
