//! The run summary (`summary.json`) and the probe table (`probes.csv`).

use std::path::Path;

use serde::Serialize;

use super::write_atomically;

/// What `summary.json` holds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// `"completed"` or `"diverged"`.
    pub status: String,
    /// The divergence report, when the run diverged.
    pub divergence: Option<String>,
    /// Integrator name.
    pub integrator: String,
    /// Frames computed.
    pub frames: u64,
    /// Steps taken.
    pub steps: u64,
    /// Step length [s].
    pub dt: f32,
    /// Steps per frame.
    pub substeps: u32,
    /// Simulated time [s].
    pub sim_time_s: f64,
    /// Wall-clock time of the frames [s], building and writing excluded.
    pub wall_time_s: f64,
    /// Mean wall-clock time per frame [ms], the probes' included.
    pub ms_per_frame: f64,
    /// Of `ms_per_frame`, the mean time the probes took [ms]: measuring a frame (the exact
    /// self-intersection count, the energies) is not simulating it, and on a scene of one
    /// step a frame it can be a sixth of the frame.
    pub probe_ms_per_frame: f64,
    /// Particles over all cloths.
    pub particles: usize,
    /// Springs over all cloths.
    pub springs: usize,
    /// Triangles over all cloths.
    pub triangles: usize,
    /// Force-model evaluations over the run.
    pub force_evaluations: u64,
    /// Rejected adaptive steps over the run.
    pub rejected_steps: u64,
    /// Conjugate-gradient iterations of the implicit methods over the run.
    pub cg_iterations: u64,
    /// Of `ms_per_frame`, the means the implicit steps spent [ms]: forces, derivatives and
    /// the system built from them ...
    pub assembly_ms_per_frame: f64,
    /// ... the preconditioner made ready for each system ...
    pub preconditioner_ms_per_frame: f64,
    /// ... and the linear solves' iterations.
    pub solve_ms_per_frame: f64,
    /// Probe values at the last frame, by name.
    pub probes: std::collections::BTreeMap<String, f64>,
}

/// Writes `value` (a [`Summary`], a bench report) as pretty JSON to `path`, whole or not
/// at all.
pub fn write_json(path: &Path, value: &impl Serialize) -> std::io::Result<()> {
    write_atomically(path, |out| {
        serde_json::to_writer_pretty(&mut *out, value).map_err(std::io::Error::other)?;
        writeln!(out)
    })
}

/// Probe values per frame, for `probes.csv`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProbeTable {
    /// Probe names, in column order (the first frame's probes, by name).
    pub columns: Vec<String>,
    /// `(frame, time [s], values)` per frame; a probe missing in a frame is left empty.
    pub rows: Vec<(u64, f64, Vec<Option<f64>>)>,
}

impl ProbeTable {
    /// Adds a row from the probes of one frame. Probes first seen now get a column of
    /// their own; earlier rows leave it empty.
    pub fn push<'a>(&mut self, frame: u64, time_s: f64, probes: impl IntoIterator<Item = (&'a str, f64)>) {
        let mut values = vec![None; self.columns.len()];
        for (name, value) in probes {
            let column = match self.columns.iter().position(|c| c == name) {
                Some(column) => column,
                None => {
                    self.columns.push(name.to_owned());
                    values.push(None);
                    self.columns.len() - 1
                }
            };
            values[column] = Some(value);
        }
        self.rows.push((frame, time_s, values));
    }

    /// Writes the table as CSV: `frame,time_s,<probe>...`.
    pub fn write_csv(&self, path: &Path) -> std::io::Result<()> {
        write_atomically(path, |out| {
            write!(out, "frame,time_s")?;
            for column in &self.columns {
                write!(out, ",{column}")?;
            }
            writeln!(out)?;
            for (frame, time, values) in &self.rows {
                write!(out, "{frame},{time}")?;
                for k in 0..self.columns.len() {
                    match values.get(k).copied().flatten() {
                        Some(value) => write!(out, ",{value}")?,
                        None => write!(out, ",")?,
                    }
                }
                writeln!(out)?;
            }
            Ok(())
        })
    }
}
