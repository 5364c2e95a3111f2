//! What arrives at each receiver, from every timed arrival's amplitude: sampled impulse
//! responses (`"impulse_response"`, [`ImpulseResponses`]) and the coherent pressure at one
//! frequency with its transmission loss ([`pressure_into`], [`transmission_loss`]).
//!
//! A solve's rays and a search's arrivals become [`Echo`]s ([`echoes_of_rays`],
//! [`echoes_of_arrivals`]): each `converged` path with an amplitude, from its source to its
//! receiver at its time. Every response is a sum over echoes, so the echoes of a scene's
//! `paths` and of its `search` can be given together.

mod echoes;
mod impulse;
mod parameters;
mod pressure;
mod pulse;
mod stream;

pub use echoes::{Echo, EchoError, echoes_of_arrivals, echoes_of_rays, echoes_of_scene};
pub use impulse::ImpulseResponses;
pub use parameters::{
    MIN_FIT_SAMPLES, RoomParameter, RoomParameters, room_parameters, schroeder_decay,
};
pub use pressure::{pressure_into, transmission_loss};
pub use pulse::FractionalDelay;
pub use stream::{
    SceneRoomParameters, Summed, echoes_of_scene_into, incoherent_loss, intensity_of_scene_into,
    pressure_of_scene_into, room_parameters_of_scene, transmission_loss_of_scene_into,
};
