//! The operational-space inverse inertia `Λ⁻¹ = J M⁻¹ Jᵀ` of a tool (RL's
//! `calculateOperationalMassMatrixInverse`).
//!
//! CRBA, the sparse `LᵀDL` factorisation, then six solves against the Jacobian's rows.
//! `q`: `nq`; result: a symmetric 6×6 in the Jacobian's row order `[linear; angular]`.
//! Does not allocate.

use crate::error::Error;
use crate::model::{Data, Model};

use super::{Jacobian, crba, factor_mass_matrix, jacobian, solve_mass_matrix};

/// `J M⁻¹ Jᵀ` for tool `tool` at `q`; `jac` receives the Jacobian on the way.
pub fn operational_inverse_inertia<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    tool: usize,
    jac: &mut Jacobian<N>,
) -> Result<[[f64; 6]; 6], Error> {
    jacobian(model, data, q, tool, jac)?;
    crba(model, data, q)?;
    factor_mass_matrix(model, data)?;
    let n = model.nv;
    let mut out = [[0.0; 6]; 6];
    let mut x = [0.0; N];
    for c in 0..6 {
        x[..n].copy_from_slice(&jac[c][..n]);
        solve_mass_matrix(model, data, &mut x[..n])?;
        for (r, row) in out.iter_mut().enumerate() {
            row[c] = jac[r][..n].iter().zip(&x[..n]).map(|(a, b)| a * b).sum();
        }
    }
    Ok(out)
}
