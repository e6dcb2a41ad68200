//! Numerics: forward-mode duals, the bounded Levenberg–Marquardt solver, the integrator
//! (generic over an [`ode::OdeSystem`] with events; it knows no creep model) and start-point
//! sampling. Imports only from [`crate::infra`].

pub mod dual;
pub mod lsq;
pub mod ode;
pub mod sampling;
pub mod scalar_min;
