//! Physics tests: eigenray's rays against closed forms and independent 1-D solves.

mod common;

mod benchmarks;
mod jacobian;
mod kinks;
mod layers;
mod mirrors;
mod regions;
mod snell;
