//! RRT-Connect with *connect* on both sides (RL's `RrtConCon`; Kuffner and LaValle, ICRA 2000,
//! the connect-connect variant): the growing tree connects towards a sample, the other tree
//! connects towards the growing tree's newest vertex; the trees swap roles every iteration.
//! The search is the one in [`super::bidirectional`].

use super::bidirectional::two_tree_planner;

two_tree_planner! {
    /// RL's `RrtConCon`.
    RrtConCon, "RRT Connect Connect",
    towards_sample: Connect, towards_tree: Connect,
}
