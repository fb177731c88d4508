//! The perturbation a run integrates: its obstacles' field (blended while it changes), its cell-mates' field, and
//! the temporal coupling's term; on a pose run with a tool, the fields act on the tool's control points instead.

use super::blend::Blend;
use super::diagnosis::Diagnosis;
use super::pose::{Chart, HeldTool};
use crate::field::RepulsiveField;
use crate::integrate::Perturbation;

/// The run's field and its cell-mates' field, summed; while a step is diagnosed, each obstacle's term is checked
/// first, at every finite state the step evaluates, until one is found that is not finite.
pub(super) struct FieldSum<'a> {
    pub(super) field: &'a mut RepulsiveField,
    /// The fields the run's field is replacing ([`super::blend`]).
    pub(super) blend: &'a mut Blend,
    pub(super) mates: &'a mut RepulsiveField,
    pub(super) diagnosis: Option<&'a mut Diagnosis>,
    /// A pose run's tool and chart: both fields act on its control points ([`super::tool`]).
    #[cfg_attr(not(feature = "orientation"), allow(dead_code))]
    pub(super) tool: Option<(&'a HeldTool, &'a Chart)>,
    /// The relative rate `tau' / tau` of the temporal coupling in force ([`super::limiting`]).
    pub(super) tau_rate: f64,
}

impl<'a> FieldSum<'a> {
    pub(super) fn new(
        field: &'a mut RepulsiveField,
        blend: &'a mut Blend,
        mates: &'a mut RepulsiveField,
        diagnosis: Option<&'a mut Diagnosis>,
        tool: Option<&'a HeldTool>,
        chart: Option<&'a Chart>,
    ) -> Self {
        Self { field, blend, mates, diagnosis, tool: tool.zip(chart), tau_rate: 0.0 }
    }

    /// With the temporal coupling's relative rate `tau' / tau` ([`super::limiting`]).
    pub(super) fn coupled(mut self, tau_rate: f64) -> Self {
        self.tau_rate = tau_rate;
        self
    }
}

impl Perturbation for FieldSum<'_> {
    /// The obstacles' and cell-mates' terms, and the temporal coupling's: `-tau' v` ([`super::limiting`]).
    fn add(&mut self, t: f64, x: &[f64], v: &[f64], tau: f64, out: &mut [f64]) {
        if self.tau_rate != 0.0 {
            let k = self.tau_rate * tau;
            out.iter_mut().zip(v).for_each(|(o, v)| *o -= k * v);
        }
        #[cfg(feature = "orientation")]
        if let Some((tool, chart)) = self.tool {
            let diagnosis = self.diagnosis.as_deref_mut();
            super::tool::add_on_tool(
                self.field, self.blend, self.mates, tool, chart, t, x, v, tau, out, diagnosis,
            );
            return;
        }
        if let Some(d) = self.diagnosis.as_deref_mut() {
            d.check(self.field, self.mates, (t, x, v, tau));
        }
        self.blend.add(self.field, t, x, v, tau, out);
        self.mates.add(t, x, v, tau, out);
    }
}
