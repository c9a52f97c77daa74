//! Rapier multibody humanoid built from URDF, the walking environment and a pendulum sanity task.
