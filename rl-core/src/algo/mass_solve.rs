//! Solving `M x = b` with the mass matrix's tree sparsity.
//!
//! `M = Lᵀ D L` with `L` unit lower triangular and nonzero only where one DOF is an ancestor
//! of the other (Featherstone, *Rigid Body Dynamics Algorithms*, Tables 6.3 and 6.4, the
//! LTDL factorisation): fill-in free, O(n·depth²). Does not allocate.
//!
//! With mimic joints that couple branches, "ancestor" is read on the elimination tree of `M`
//! (worked out once when the model is built, see [`crate::model::mimic`]), whose paths cover
//! the fill-in; without them it is the tree of the degrees of freedom itself.
//!
//! Errors: [`Error::NotPositiveDefinite`] names the DOF whose pivot is not positive (a joint
//! that moves no mass or inertia).

use crate::error::{Error, check_len};
use crate::model::{Data, Model, ROOT};

/// Factors the mass matrix of the last [`super::crba`] call into `data` (kept beside it).
pub fn factor_mass_matrix<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
) -> Result<(), Error> {
    let n = model.nv;
    let h = &mut data.factor;
    for r in 0..n {
        for c in 0..n {
            h[r][c] = if r <= c {
                data.mass_matrix[r][c]
            } else {
                data.mass_matrix[c][r]
            };
        }
    }
    for k in (0..n).rev() {
        if h[k][k] <= 0.0 || !h[k][k].is_finite() {
            return Err(Error::NotPositiveDefinite { dof: k });
        }
        let mut i = model.dof_parent[k];
        while i != ROOT {
            let a = h[k][i] / h[k][k];
            let mut j = i;
            while j != ROOT {
                h[i][j] -= h[k][j] * a;
                j = model.dof_parent[j];
            }
            h[k][i] = a;
            i = model.dof_parent[i];
        }
    }
    Ok(())
}

/// Solves `M x = b` in place (`b` becomes `x`), after [`factor_mass_matrix`].
pub fn solve_mass_matrix<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    b: &mut [f64],
) -> Result<(), Error> {
    check_len("b", b, model.nv)?;
    let n = model.nv;
    let h = &data.factor;
    // Lᵀ y = b
    for i in (0..n).rev() {
        let mut j = model.dof_parent[i];
        while j != ROOT {
            b[j] -= h[i][j] * b[i];
            j = model.dof_parent[j];
        }
    }
    // D z = y
    for (i, x) in b.iter_mut().enumerate() {
        *x /= h[i][i];
    }
    // L x = z
    for i in 0..n {
        let mut j = model.dof_parent[i];
        while j != ROOT {
            b[i] -= h[i][j] * b[j];
            j = model.dof_parent[j];
        }
    }
    Ok(())
}
