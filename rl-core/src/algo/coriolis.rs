//! Velocity-dependent joint forces: Coriolis and centrifugal `C(q, q̇)`, and with gravity the
//! nonlinear effects `C + G` (what Pinocchio calls `nle`).
//!
//! RNEA with `q̈ = 0`. `q`: `nq`, `qd`: `dof`; result: `dof`. O(n). Does not allocate.

use crate::error::{Error, check_len};
use crate::model::{Data, Model};

/// `C(q, q̇)` (without gravity).
pub fn coriolis<'d, const N: usize>(
    model: &Model<N>,
    data: &'d mut Data<N>,
    q: &[f64],
    qd: &[f64],
) -> Result<&'d [f64], Error> {
    check_len("q", q, model.nq)?;
    check_len("qd", qd, model.nv)?;
    super::rnea::inverse_dynamics(model, data, q, Some(qd), None, false, None);
    Ok(&data.tau[..model.nv])
}

/// `C(q, q̇) + G(q)`.
pub fn nonlinear_effects<'d, const N: usize>(
    model: &Model<N>,
    data: &'d mut Data<N>,
    q: &[f64],
    qd: &[f64],
) -> Result<&'d [f64], Error> {
    check_len("q", q, model.nq)?;
    check_len("qd", qd, model.nv)?;
    super::rnea::inverse_dynamics(model, data, q, Some(qd), None, true, None);
    Ok(&data.tau[..model.nv])
}
