//! Six waypoints of a 7-axis arm with their times, shared by the trajectory tests and the
//! trajectory benchmark (`benches/traj.rs` includes this file by path).

/// Waypoint times, s.
pub const TIMES: [f64; 6] = [0.0, 0.5, 1.2, 2.0, 2.4, 3.0];

/// Joint positions at [`TIMES`], rad.
pub const POINTS: [[f64; 7]; 6] = [
    [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
    [0.5, -0.1, 0.0, 0.8, 0.1, 0.0, -0.6],
    [1.0, 0.3, -0.4, 0.2, 0.0, 0.9, 0.2],
    [0.2, 0.5, 0.1, -0.3, 0.6, 0.3, 0.0],
    [-0.4, 0.0, 0.7, 0.0, 0.2, -0.2, 0.4],
    [0.0, 0.2, 0.3, 0.1, -0.5, 0.1, 0.2],
];
