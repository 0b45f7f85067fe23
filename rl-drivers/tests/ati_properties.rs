//! The Net F/T codec never panics on any input, and what it encodes decodes to itself.

use proptest::prelude::*;
use rl_drivers::proto::netft::{
    CALINFO_RESPONSE_LEN, Calibration, ForceUnit, RECORD_LEN, RdtCommand, RdtRecord, RdtRequest,
    TorqueUnit, decode_tcp_request, records,
};

proptest! {
    #[test]
    fn decoders_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = RdtRequest::decode(&bytes);
        let _ = RdtRecord::decode(&bytes);
        if let Ok(rs) = records(&bytes) {
            prop_assert_eq!(rs.count(), bytes.len() / RECORD_LEN);
        }
        let _ = Calibration::decode(&bytes);
        let _ = decode_tcp_request(&bytes);
    }

    #[test]
    fn records_round_trip(
        rdt in any::<u32>(), ft in any::<u32>(), status in any::<u32>(),
        counts in proptest::array::uniform6(any::<i32>()),
    ) {
        let r = RdtRecord { rdt_sequence: rdt, ft_sequence: ft, status, counts };
        prop_assert_eq!(RdtRecord::decode(&r.to_bytes()), Ok(r));
    }

    #[test]
    fn requests_round_trip(k in 0usize..6, count in any::<u32>()) {
        let command = [
            RdtCommand::Stop, RdtCommand::StartRealTime, RdtCommand::StartBuffered,
            RdtCommand::StartMultiUnit, RdtCommand::ResetThresholdLatch, RdtCommand::SetSoftwareBias,
        ][k];
        let r = RdtRequest::new(command, count);
        prop_assert_eq!(RdtRequest::decode(&r.to_bytes()), Ok(r));
    }

    #[test]
    fn calibrations_round_trip_and_scale_within_half_a_count(
        cpf in 1u32.., cpt in 1u32.., fu in 0usize..6, tu in 0usize..6,
        scale in proptest::array::uniform6(any::<u16>()),
        wrench in proptest::array::uniform6(-1000.0f64..1000.0),
    ) {
        let c = Calibration {
            counts_per_force: cpf, counts_per_torque: cpt,
            force_unit: ForceUnit::ALL[fu], torque_unit: TorqueUnit::ALL[tu],
            scale_factors: scale,
        };
        let bytes = c.to_bytes();
        prop_assert_eq!(bytes.len(), CALINFO_RESPONSE_LEN);
        prop_assert_eq!(Calibration::decode(&bytes), Ok(c));
        let counts = c.to_counts(&wrench);
        let back = c.to_si(&counts);
        for k in 0..6 {
            let per = if k < 3 { c.newton_per_count() } else { c.newton_metre_per_count() };
            let raw = wrench[k] / per;
            if raw.abs() < f64::from(i32::MAX) - 1.0 {
                prop_assert!((back[k] - wrench[k]).abs() <= 0.5 * per * (1.0 + 1e-9));
            }
        }
    }
}
