//! Every frame of every real-hardware capture (tests/data/ecat) decodes with our codec exactly
//! as Wireshark's `ecat` dissector (tshark, not written here) decodes it: the same datagrams with
//! the same command, index, addresses, length and working counter; frames tshark does not read as
//! EtherCAT datagrams (IP, ARP, LLDP, EtherCAT over UDP, runts) are refused with a typed error.
//! Skips with a printed reason only if tshark is not installed (scripts/test installs it).

mod support;

use std::path::Path;
use std::process::Command;

use rl_drivers::proto::ecat::Frame;
use rl_drivers::proto::ecat::frame::FrameError;

/// One datagram as tshark prints it.
#[derive(Debug, PartialEq, Eq, Clone)]
struct Dissected {
    cmd: u8,
    idx: u8,
    /// ADP/ADO, or the logical address.
    address: Address,
    len: u16,
    wkc: u16,
}

#[derive(Debug, PartialEq, Eq, Clone, Copy)]
enum Address {
    Physical { adp: u16, ado: u16 },
    Logical(u32),
}

fn num(s: &str) -> u64 {
    let s = s.trim();
    match s.strip_prefix("0x") {
        Some(h) => u64::from_str_radix(h, 16),
        None => s.parse(),
    }
    .unwrap_or_else(|e| panic!("tshark field {s:?}: {e}"))
}

fn list(s: &str) -> Vec<u64> {
    if s.trim().is_empty() {
        Vec::new()
    } else {
        s.split(',').map(num).collect()
    }
}

/// tshark's datagrams per frame (index = frame number − 1; empty: not dissected as EtherCAT).
fn tshark(file: &Path) -> Option<Vec<Vec<Dissected>>> {
    let out = Command::new("tshark")
        .arg("-r")
        .arg(file)
        .args(["-T", "fields", "-E", "occurrence=a", "-E", "separator=/t"])
        .args(["-e", "frame.number", "-e", "ecat.cmd", "-e", "ecat.idx"])
        .args(["-e", "ecat.adp", "-e", "ecat.ado", "-e", "ecat.lad"])
        .args(["-e", "ecat.subframe.length", "-e", "ecat.cnt"])
        .output()
        .ok()?;
    assert!(
        out.status.success(),
        "tshark failed on {}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let mut frames = Vec::new();
    for line in String::from_utf8(out.stdout).expect("utf-8").lines() {
        let f: Vec<&str> = line.split('\t').collect();
        assert_eq!(f.len(), 8, "tshark line {line:?}");
        assert_eq!(
            num(f[0]) as usize,
            frames.len() + 1,
            "frame numbers in order"
        );
        let cmds = list(f[1]);
        let (idx, adp, ado, lad, len, cnt) = (
            list(f[2]),
            list(f[3]),
            list(f[4]),
            list(f[5]),
            list(f[6]),
            list(f[7]),
        );
        let (mut p, mut l) = (0, 0);
        let mut dg = Vec::new();
        for (k, &cmd) in cmds.iter().enumerate() {
            let address = if (10..=12).contains(&cmd) {
                l += 1;
                Address::Logical(lad[l - 1] as u32)
            } else {
                p += 1;
                Address::Physical {
                    adp: adp[p - 1] as u16,
                    ado: ado[p - 1] as u16,
                }
            };
            dg.push(Dissected {
                cmd: cmd as u8,
                idx: idx[k] as u8,
                address,
                len: len[k] as u16,
                wkc: cnt[k] as u16,
            });
        }
        frames.push(dg);
    }
    Some(frames)
}

fn ours(bytes: &[u8]) -> Result<Vec<Dissected>, FrameError> {
    let frame = Frame::decode(bytes)?;
    Ok(frame
        .datagrams()
        .map(|d| {
            let d = d.expect("checked by decode");
            let h = d.header;
            Dissected {
                cmd: h.cmd,
                idx: h.index,
                address: if h.command().is_some_and(|c| c.is_logical()) {
                    Address::Logical(h.address)
                } else {
                    Address::Physical {
                        adp: h.adp(),
                        ado: h.ado(),
                    }
                },
                len: h.len,
                wkc: d.wkc,
            }
        })
        .collect())
}

#[test]
fn every_capture_frame_decodes_as_tshark_dissects_it() {
    if Command::new("tshark").arg("--version").output().is_err() {
        println!("SKIPPED: tshark is not installed (apt-get install tshark; scripts/test does)");
        return;
    }
    let files = support::captures();
    assert_eq!(files.len(), 11, "the eleven captures of tests/data/ecat");
    let (mut datagrams, mut frames, mut refused) = (0usize, 0usize, 0usize);
    for file in files {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let packets = support::read_pcapng(&file);
        let dissected = tshark(&file).expect("tshark runs");
        assert_eq!(packets.len(), dissected.len(), "{name}: frame count");
        let mut ecat_frames = 0;
        for (k, (p, want)) in packets.iter().zip(&dissected).enumerate() {
            let n = k + 1;
            match ours(&p.data) {
                Ok(got) => {
                    assert_eq!(&got, want, "{name} frame {n}");
                    ecat_frames += 1;
                    datagrams += got.len();
                }
                Err(e) => {
                    assert!(
                        want.is_empty(),
                        "{name} frame {n}: tshark dissects {} datagrams, we refuse: {e}",
                        want.len()
                    );
                    assert!(
                        matches!(
                            e,
                            FrameError::NotEthercat { .. } | FrameError::TooShort { .. }
                        ),
                        "{name} frame {n}: {e}"
                    );
                    refused += 1;
                }
            }
        }
        assert!(ecat_frames > 0, "{name}: no EtherCAT frame");
        frames += ecat_frames;
    }
    println!(
        "{frames} EtherCAT frames, {datagrams} datagrams agree with tshark; {refused} other frames refused"
    );
}
