//! RRT-Connect with *connect* on both sides (RL's `RrtConCon`; Kuffner and LaValle, ICRA 2000,
//! the connect-connect variant): the growing tree connects towards a sample, the other tree
//! connects towards the growing tree's newest vertex; the trees swap roles every iteration.
//! A connect adds one vertex, at its last valid step, as RL's does (not one per step: a tree
//! that grew a vertex per step had 20–110× more vertices than RL's on RL's scenarios, and its
//! nearest-neighbour searches took the time). The search is the one in
//! [`super::bidirectional`].

use super::bidirectional::two_tree_planner;

two_tree_planner! {
    /// RL's `RrtConCon`.
    RrtConCon, "RRT Connect Connect",
    towards_sample: ConnectOnce, towards_tree: ConnectOnce,
}
