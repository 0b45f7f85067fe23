//! RRT-Connect as Kuffner and LaValle published it (ICRA 2000), RL's `RrtExtCon`, OMPL's
//! `RRTConnect` and VAMP's `RRTC`: the growing tree *extends* one step towards a sample
//! (within the settings' dynamic domain when they have one), the other tree *connects*
//! towards the new vertex; the trees swap roles (or, with `balance`, the smaller one grows).
//! The search is the one in [`super::bidirectional`].

use super::bidirectional::two_tree_planner;

two_tree_planner! {
    /// RL's `RrtExtCon`.
    RrtExtCon, "RRT Extend Connect",
    towards_sample: ExtendInDomain, towards_tree: Connect,
}
