//! The generalized gravity vector `G(q)`: the joint forces that hold the robot still.
//!
//! RNEA with `q̇ = q̈ = 0`, skipping the velocity terms. `q`: `nq`; result: `dof`. O(n).
//! Does not allocate.

use crate::error::{Error, check_len};
use crate::model::{Data, Model};

/// `G(q)`.
pub fn gravity<'d, const N: usize>(
    model: &Model<N>,
    data: &'d mut Data<N>,
    q: &[f64],
) -> Result<&'d [f64], Error> {
    check_len("q", q, model.nq)?;
    super::rnea::run(model, data, q, None, None, true, None);
    Ok(&data.tau[..model.nv])
}
