//! The element library: force elements on nodes (the contract is [`crate::core::Element`]).

pub mod aero;
mod applied_load;
pub mod beam;
mod contact;
mod controller;
mod dc_motor;
mod granular;
mod hydraulic;
pub mod line_of_action;
mod low_pass;
mod maxwell;
mod node_dual;
mod rigid_body;
mod rolling;
mod slot;
mod sphere_pair;
mod spring_damper;
pub mod terrain;
mod time_signal;
mod tire;

pub use applied_load::{AppliedLoad, LoadFrame};
pub use contact::{
    Contact, ContactShape, Friction, GroundPlane, NormalLaw, hunt_crossley_damping, normal_force,
};
pub use controller::{Block as ControllerBlock, Controller, Pid, lookup as controller_lookup};
pub use dc_motor::DcMotor;
pub use granular::GranularSet;
pub use hydraulic::{
    GasCharge, HydraulicCircuit, Multiplier as OrificeMultiplier, Orifice as HydraulicOrifice,
    OrificeLaw, Port, Volume as HydraulicVolume, actuator as hydraulic_actuator,
};
pub use low_pass::{LowPassSensor, NodeQuantity, SensorInput};
pub use maxwell::Maxwell;
pub use rigid_body::RigidBody;
pub use rolling::RollingResistance;
pub use sphere_pair::{PairFriction, SpherePair};
pub use spring_damper::SpringDamper;
pub use time_signal::TimeSignal;
pub use tire::{MagicFormula, Tire, TireGround, TireParameters};

pub use crate::core::{Element, EvalContext, LocalTerms, Need, add_block};
