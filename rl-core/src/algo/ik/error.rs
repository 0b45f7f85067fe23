//! Why inverse kinematics refused its input or gave up.

use core::fmt;

/// The error of [`super::IkSolver::solve`]: bad input (nothing was tried) or no solution
/// within the budgets (the best configuration found is in the caller's buffer).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IkError {
    /// A vector argument has the wrong length.
    Dimension {
        /// The argument's name (`"q_init"`, `"q_out"`).
        argument: &'static str,
        /// The length the model needs.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// No goals were given.
    NoGoals,
    /// More goals than [`super::MAX_GOALS`].
    TooManyGoals {
        /// The number given.
        got: usize,
    },
    /// A goal names a tool the model does not have.
    UnknownTool {
        /// The goal's index in the slice.
        goal: usize,
        /// The tool index it names.
        tool: usize,
    },
    /// A goal's target is not finite, or its rotation is not a rotation matrix.
    InvalidGoal {
        /// The goal's index in the slice.
        goal: usize,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// The start configuration contains a NaN or an infinity.
    NotFiniteStart {
        /// The index into `q_init`.
        index: usize,
    },
    /// An option is out of range (negative damping, zero epsilon, ...).
    InvalidOption {
        /// The option's name.
        option: &'static str,
    },
    /// The iteration budget (or the restart limit) ran out before the error fell below
    /// epsilon.
    NotConverged {
        /// The smallest residual `|dx|` reached (m and rad stacked).
        residual: f64,
        /// Iterations spent in total.
        iterations: usize,
        /// Random restarts made.
        restarts: usize,
    },
    /// The time budget ran out before the error fell below epsilon.
    TimeBudget {
        /// The smallest residual `|dx|` reached.
        residual: f64,
        /// Iterations spent in total.
        iterations: usize,
        /// Random restarts made.
        restarts: usize,
    },
}

impl fmt::Display for IkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            // The same wording as the dynamics' dimension error.
            &IkError::Dimension {
                argument,
                expected,
                got,
            } => crate::Error::Dimension {
                argument,
                expected,
                got,
            }
            .fmt(f),
            IkError::NoGoals => f.write_str("inverse kinematics needs at least one goal"),
            IkError::TooManyGoals { got } => {
                write!(
                    f,
                    "{got} goals given, at most {} are supported",
                    super::MAX_GOALS
                )
            }
            IkError::UnknownTool { goal, tool } => {
                write!(
                    f,
                    "goal {goal} names tool {tool}, which the model does not have"
                )
            }
            IkError::InvalidGoal { goal, reason } => write!(f, "goal {goal}: {reason}"),
            IkError::NotFiniteStart { index } => {
                write!(f, "start configuration element {index} is not finite")
            }
            IkError::InvalidOption { option } => write!(f, "option `{option}` is out of range"),
            IkError::NotConverged {
                residual,
                iterations,
                restarts,
            } => write!(
                f,
                "no solution after {iterations} iterations and {restarts} restarts \
                 (best residual {residual:e})"
            ),
            IkError::TimeBudget {
                residual,
                iterations,
                restarts,
            } => write!(
                f,
                "time budget spent after {iterations} iterations and {restarts} restarts \
                 (best residual {residual:e})"
            ),
        }
    }
}

impl core::error::Error for IkError {}
