//! Any bytes as an SII image: every reader (identity, strings, categories, PDOs, sync managers,
//! distributed clocks) answers or returns an error, never panics.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rl_drivers::proto::ecat::sii::Sii;

fuzz_target!(|data: &[u8]| {
    let sii = Sii::new(data);
    let _ = (sii.vendor_id(), sii.mailbox_in(), sii.name(), sii.general(), sii.checksum_ok());
    for c in sii.categories() {
        let _ = c;
    }
    for p in sii.pdos(true).chain(sii.pdos(false)).flatten() {
        let _ = p.bits();
    }
    if let Ok(s) = sii.sync_managers() {
        let _ = s.count();
    }
    if let Ok(m) = sii.dc_modes() {
        let _ = m.count();
    }
    for k in 0..=255u8 {
        let _ = sii.string(k);
    }
});
