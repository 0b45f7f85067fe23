//! Model loading: RL XML and URDF (being built).
