//! Behaviour: the scheduled systems, one module per stage. Each is a thin adapter that
//! queries components, calls kernels from [`crate::solver`] and writes results back.
//! Each module's `add_to` places its systems into the sets of [`crate::schedule`].

pub mod constraints;
pub mod contacts;
pub mod finish;
pub mod forces;
pub mod input;
pub mod integrate;
pub mod prepare;
pub mod props;
pub mod substeps;
pub mod writeback;

use crate::schedule::SimSchedules;

/// Adds every system to its set.
pub fn add_to(schedules: &mut SimSchedules) {
    input::add_to(schedules);
    prepare::add_to(schedules);
    substeps::add_to(schedules);
    props::add_to(schedules);
    forces::add_to(schedules);
    integrate::add_to(schedules);
    constraints::add_to(schedules);
    contacts::add_to(schedules);
    finish::add_to(schedules);
    writeback::add_to(schedules);
}
