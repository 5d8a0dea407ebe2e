//! Cloth: garments simulated on the posed body's collision capsules (work in progress).

pub mod capsule;

pub use capsule::Capsule;
