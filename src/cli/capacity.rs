//! The one place where the `rl` tool chooses the capacity of the models it loads at run time.
//!
//! `rl_core::Model<N>` holds at most `N` bodies, `N` degrees of freedom (mimic joints' internal
//! coordinates included) and `N` tools, decided at compile time. The tool is built for the
//! few capacities in [`CAPACITIES`] and gives each file the smallest one that holds it: arms
//! run in small, cache-friendly models, and robots of up to [`LARGEST`] bodies and degrees of
//! freedom load at all. Every subcommand that loads a model goes through [`load`] with a
//! [`WithModel`] job, whose `run::<N>` is monomorphised once per capacity, e.g.:
//!
//! ```ignore
//! struct Info;
//! impl WithModel for Info {
//!     type Output = usize;
//!     fn run<const N: usize>(self, m: Box<LoadedModel<N>>) -> Result<usize, CliError> {
//!         Ok(m.model.dof())
//!     }
//! }
//! let dof = capacity::load(path, &LoadOptions::default(), Info)?;
//! ```
//!
//! A model over the largest capacity is refused with a message that says which capacity it
//! exceeds and how to choose a bigger one (add it here and rebuild).

use std::path::Path;

use rl_core::loader::{self, LoadError, LoadErrorKind, LoadOptions, LoadedModel};
use rl_core::model::ModelError;

use super::CliError;

/// Defines [`CAPACITIES`] and the loader that tries them in order, from one list.
macro_rules! capacities {
    ($($n:literal),+) => {
        /// The capacities the tool is built for, ascending.
        pub const CAPACITIES: &[usize] = &[$($n),+];

        /// Loads `text` into the first capacity that holds it and runs `job` on it; the
        /// capacity error of the largest when none does.
        #[allow(unused_assignments)] // each capacity's error is kept only for the last
        fn dispatch<J: WithModel>(
            text: &str,
            options: &LoadOptions,
            job: J,
        ) -> Result<Result<J::Output, CliError>, LoadError> {
            let mut last = None;
            $(
                match loader::load_str_options::<$n>(text, options) {
                    Ok(m) => return Ok(job.run::<$n>(Box::new(m))),
                    Err(e) if over_capacity(&e) => last = Some(e),
                    Err(e) => return Err(e),
                }
            )+
            Err(last.unwrap_or(LoadError {
                path: None,
                element: None,
                kind: LoadErrorKind::Model(ModelError::TooManyBodies { capacity: 0 }),
            }))
        }
    };
}

capacities!(16, 64, 256);

/// The largest: bodies, degrees of freedom and tools of the largest model the tool loads.
pub const LARGEST: usize = CAPACITIES[CAPACITIES.len() - 1];

/// Something to do with a model whose capacity is chosen when the file is read.
pub trait WithModel {
    /// What the job returns.
    type Output;
    /// Runs the job on the loaded model (boxed: the larger capacities are large values).
    fn run<const N: usize>(self, loaded: Box<LoadedModel<N>>) -> Result<Self::Output, CliError>;
}

/// Loads `path` into the smallest capacity of [`CAPACITIES`] that holds it and runs `job` on it.
/// The file is read once. Load errors become usage errors whose message names the tool's flags
/// where one helps ([`load_error`]).
pub fn load<J: WithModel>(
    path: &Path,
    options: &LoadOptions,
    job: J,
) -> Result<J::Output, CliError> {
    read_and_load(path, options, job)?
}

/// [`load`] for the file given to `flag`: a load error starts with the flag's name (`--model:
/// …`); what `job` returns is passed on as it is.
pub fn load_for<J: WithModel>(
    flag: &str,
    path: &Path,
    options: &LoadOptions,
    job: J,
) -> Result<J::Output, CliError> {
    read_and_load(path, options, job).map_err(|e| e.prefixed(flag))?
}

/// [`load`] for a model that is not a file (one built into the tool), named `name` in errors.
pub fn load_text<J: WithModel>(
    name: &str,
    text: &str,
    options: &LoadOptions,
    job: J,
) -> Result<J::Output, CliError> {
    load_in(Path::new(name), text, options, job)?
}

/// Reads `path` and loads it: the outer error is the load's, the inner the job's.
fn read_and_load<J: WithModel>(
    path: &Path,
    options: &LoadOptions,
    job: J,
) -> Result<Result<J::Output, CliError>, CliError> {
    // At most the size limit is read; a FIFO or a device is refused unread.
    let text = rl_core::loader::read_text(path, options.input.max_bytes)
        .map_err(|e| load_error(LoadError::from(e)))?;
    load_in(path, &text, options, job)
}

/// Loads `text` (from `path`, for errors) into the first capacity that holds it.
fn load_in<J: WithModel>(
    path: &Path,
    text: &str,
    options: &LoadOptions,
    job: J,
) -> Result<Result<J::Output, CliError>, CliError> {
    match dispatch(text, options, job) {
        Ok(out) => Ok(out),
        Err(mut e) => {
            e.path = Some(path.to_path_buf());
            if !over_capacity(&e) {
                return Err(load_error(e));
            }
            Err(CliError::usage(format!(
                "{e}. The rl tool loads models into the capacities {CAPACITIES:?} (most bodies, \
                 degrees of freedom and tools; src/cli/capacity.rs) and this one needs more than \
                 {LARGEST}: add a larger capacity to CAPACITIES there and rebuild rl, or load the \
                 file in your own program into a larger model, e.g. \
                 rl_core::loader::load_file::<512>(path)"
            )))
        }
    }
}

/// Whether `e` says the model does not fit its capacity.
fn over_capacity(e: &LoadError) -> bool {
    matches!(
        e.kind,
        LoadErrorKind::Model(
            ModelError::TooManyBodies { .. }
                | ModelError::TooManyDofs { .. }
                | ModelError::TooManyTools { .. }
        )
    )
}

/// A load error as the tool shows it: the message, and the flag that changes the outcome where
/// there is one.
pub fn load_error(e: LoadError) -> CliError {
    let hint = match &e.kind {
        LoadErrorKind::Mimic { .. } => {
            "; --mimic-independent loads mimic joints as independent joints"
        }
        LoadErrorKind::UnphysicalInertia { problem, .. } => match problem {
            rl_core::spatial::InertiaProblem::TriangleInequality { .. } => {
                "; --inertia-check definite (the default) or lenient loads it with a warning"
            }
            _ => "; --inertia-check lenient loads it with a warning (the dynamics may be wrong)",
        },
        _ => "",
    };
    CliError::usage(format!("{e}{hint}"))
}
