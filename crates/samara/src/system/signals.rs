//! Signals: named scalars that elements compute from their own unknowns and that other
//! elements and constraints read in the same Newton iteration (ARCHITECTURE.md, "Element
//! states").
//!
//! A signal s produced by element p depends on p's local unknowns x_p and on p's input
//! signals: `s = g(x_p, s_in)`. Its derivative with respect to the configuration
//! unknowns follows by the chain rule in evaluation order,
//!
//! `∂s/∂x = ∂g/∂x_p + Σ_j (∂g/∂s_j) ∂s_j/∂x`,
//!
//! in three channels like the element tangents (K: value, C: rate, M: acceleration). The
//! *support* of a signal is the set of configuration unknowns it depends on; a consumer's
//! rows couple to every unknown of the supports of its inputs. Producers are evaluated in
//! an order where every input with feedthrough is known first; a loop of signals through
//! elements that all have feedthrough has no such order and is reported.
//!
//! Besides the signals elements produce, a consumer may read (names with a colon):
//! - a joint coordinate or an element state, directly ([`DirectSource`]);
//! - an element's output, `output:<element>.<output>` (the results' `element_output`
//!   names): a signal of the element, `g = y(x_p, s_in)`, with the derivatives of
//!   [`super::probe`]; it counts as depending directly on the element's input signals;
//! - a joint reaction, `joint_force:<joint>.<x|y|z>`, `joint_moment:<joint>.<x|y|z>`
//!   (frame A, as written in the results) or `joint_coordinate_force:<joint>.<component>`
//!   ([`ReactionSource`]): the multipliers are not configuration unknowns, so these are
//!   held values (in [`State::held`], after the elements' own), set from the converged
//!   solution after each step ([`super::System::hold_reactions`]); within a step they are
//!   constants (no derivatives, empty support).

use super::probe::{ProbeWork, output_terms};
use crate::core::{Element, ElementInput, EvalContext, SignalTerms, State};

/// Index of a node unknown, a joint coordinate or an element state in the configuration
/// vector `[6 per node | active joint coordinates | element states]`.
pub type ConfigIndex = usize;

/// What went wrong when connecting the signals (a validated model has none of these).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SignalIssue {
    /// A consumer reads a signal nobody produces (it reads 0).
    Unknown { consumer: String, signal: String },
    /// Two producers of one name (the first is used).
    Duplicate { signal: String },
    /// Signals that depend on each other without a state in between.
    Loop { signals: Vec<String> },
}

impl std::fmt::Display for SignalIssue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SignalIssue::Unknown { consumer, signal } => {
                write!(
                    f,
                    "'{consumer}' reads signal '{signal}', which nothing produces"
                )
            }
            SignalIssue::Duplicate { signal } => write!(f, "signal '{signal}' is produced twice"),
            SignalIssue::Loop { signals } => write!(
                f,
                "the signals {} form an algebraic loop (no element with a state breaks it)",
                signals.join(" → ")
            ),
        }
    }
}

/// The signals of a system: who produces what, who reads what, in which order to compute
/// them, and on which unknowns each depends.
#[derive(Clone, Debug, Default)]
pub struct SignalGraph {
    pub names: Vec<String>,
    /// Producing element and its output index, per signal (`None`: unknown, reads 0).
    pub producer: Vec<Option<(usize, usize)>>,
    /// Signal ids read by each element, in its `signal_inputs` order.
    pub element_inputs: Vec<Vec<usize>>,
    /// Signal id of each output of each element (`None` for a duplicate name).
    pub element_outputs: Vec<Vec<Option<usize>>>,
    /// Signal ids read by each constraint.
    pub constraint_inputs: Vec<Vec<usize>>,
    /// Producing elements in evaluation order.
    pub order: Vec<usize>,
    /// Sorted configuration indices each signal depends on.
    pub support: Vec<Vec<ConfigIndex>>,
    /// Per signal: position in its support of each local unknown of its producer.
    local_pos: Vec<Vec<usize>>,
    /// Per signal and producer input j: position in the signal's support of each entry of
    /// input j's support.
    input_pos: Vec<Vec<Vec<usize>>>,
    /// Issues found while connecting.
    pub issues: Vec<SignalIssue>,
    /// Signals read straight from one unknown of the configuration (a joint coordinate
    /// or an element state, [`DirectSource`]): (signal id, source).
    pub direct: Vec<(usize, DirectSource)>,
    /// Offset of each element's sample-and-hold values in [`State::held`], and their
    /// number with the held reactions.
    held_offsets: Vec<usize>,
    n_held: usize,
    /// Element outputs read as signals: per element, the output indices and their signal
    /// ids (empty for elements nobody probes).
    pub probe_outputs: Vec<Vec<usize>>,
    pub probe_ids: Vec<Vec<usize>>,
    /// Number of outputs of each probed element (0 for the others).
    probe_counts: Vec<usize>,
    /// Joint reactions read as signals: (signal id, source); the value of the i-th is
    /// held in [`State::held`] at `n_held − reactions.len() + i`.
    pub reactions: Vec<(usize, ReactionSource)>,
}

/// A joint reaction read as a signal: component `component` (frame A) of the reaction
/// force or moment of constraint `constraint`, or the generalized force on active joint
/// coordinate `coordinate` (index into [`State::coords`]), as the results write them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReactionSource {
    Force { constraint: usize, component: usize },
    Moment { constraint: usize, component: usize },
    CoordinateForce { coordinate: usize },
}

impl ReactionSource {
    /// The source named `joint_force:<joint>.<x|y|z>`, `joint_moment:…` or
    /// `joint_coordinate_force:<joint>.<component>`, with `joints` the constraint names
    /// and `coordinates` the active coordinate names (`<joint>.<component>`).
    pub fn resolve(name: &str, joints: &[&str], coordinates: &[String]) -> Option<Self> {
        let (kind, what) = name.split_once(':')?;
        if kind == "joint_coordinate_force" {
            let coordinate = coordinates.iter().position(|c| c == what)?;
            return Some(Self::CoordinateForce { coordinate });
        }
        let (joint, comp) = what.rsplit_once('.')?;
        let component = ["x", "y", "z"].iter().position(|c| *c == comp)?;
        let constraint = joints.iter().position(|j| *j == joint)?;
        match kind {
            "joint_force" => Some(Self::Force {
                constraint,
                component,
            }),
            "joint_moment" => Some(Self::Moment {
                constraint,
                component,
            }),
            _ => None,
        }
    }
}

/// What a direct signal reads: a joint coordinate's value, rate or acceleration
/// (`channel` 0, 1, 2; `index` into [`State::coords`]) or an element state's value or
/// rate (`index` into [`State::states`]). Named `coordinate:<joint>.<component>`,
/// `coordinate_rate:…`, `coordinate_acceleration:…`, `state:<element>.<state>`,
/// `state_rate:…`; nothing else produces names with a colon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DirectSource {
    pub coordinate: bool,
    pub index: usize,
    pub channel: usize,
    pub config: ConfigIndex,
}

/// The unknowns direct signals may read: active coordinate names (in state order) and
/// element state names, with the configuration offsets of both.
#[derive(Clone, Copy, Debug)]
pub struct DirectNames<'a> {
    pub coordinates: &'a [String],
    pub states: &'a [String],
    pub first_coordinate: ConfigIndex,
    pub first_state: ConfigIndex,
}

impl DirectNames<'_> {
    /// The source a direct signal name designates, if any.
    pub fn resolve(&self, name: &str) -> Option<DirectSource> {
        let (kind, what) = name.split_once(':')?;
        let (coordinate, channel) = match kind {
            "coordinate" => (true, 0),
            "coordinate_rate" => (true, 1),
            "coordinate_acceleration" => (true, 2),
            "state" => (false, 0),
            "state_rate" => (false, 1),
            _ => return None,
        };
        let (list, first) = if coordinate {
            (self.coordinates, self.first_coordinate)
        } else {
            (self.states, self.first_state)
        };
        let index = list.iter().position(|n| n == what)?;
        Some(DirectSource {
            coordinate,
            index,
            channel,
            config: first + index,
        })
    }
}

/// Values and configuration derivatives of all signals at one state (scratch reused across
/// evaluations: nothing is allocated per call).
#[derive(Clone, Debug, Default)]
pub struct SignalValues {
    pub values: Vec<f64>,
    /// Per signal, per support entry: `[∂s/∂q, ∂s/∂v, ∂s/∂v̇]` (for states: value, rate, 0).
    pub gradients: Vec<Vec<[f64; 3]>>,
    terms: Vec<Option<SignalTerms>>,
    /// Per element: the values and derivatives of its probed outputs.
    probe_terms: Vec<Option<SignalTerms>>,
    probe_work: ProbeWork,
    inputs: Vec<f64>,
}

impl SignalGraph {
    /// Connects the signals of `elements` and `constraint_inputs` (names read by each
    /// constraint). `local_config[e]` lists the configuration index of each local unknown
    /// of element e.
    pub fn build(
        elements: &[Box<dyn Element>],
        constraint_inputs: &[(String, Vec<String>)],
        local_config: &[Vec<ConfigIndex>],
        direct: DirectNames,
    ) -> Self {
        let mut g = SignalGraph::default();
        for e in elements {
            g.held_offsets.push(g.n_held);
            g.n_held += e.n_held();
        }
        g.probe_outputs = vec![Vec::new(); elements.len()];
        g.probe_ids = vec![Vec::new(); elements.len()];
        g.probe_counts = vec![0; elements.len()];
        let joints: Vec<&str> = constraint_inputs.iter().map(|c| c.0.as_str()).collect();
        // `<element>.<output>` per element, listed when a consumer first reads an output.
        let mut output_names: Option<Vec<Vec<String>>> = None;
        let mut id = std::collections::HashMap::new();
        for (k, e) in elements.iter().enumerate() {
            let mut outs = Vec::new();
            for (o, name) in e.signal_outputs().iter().enumerate() {
                if id.contains_key(name) {
                    g.issues.push(SignalIssue::Duplicate {
                        signal: name.clone(),
                    });
                    outs.push(None);
                    continue;
                }
                id.insert(name.clone(), g.names.len());
                outs.push(Some(g.names.len()));
                g.names.push(name.clone());
                g.producer.push(Some((k, o)));
            }
            g.element_outputs.push(outs);
        }
        let mut resolve = |g: &mut SignalGraph, consumer: &str, name: &String| -> usize {
            if let Some(&s) = id.get(name) {
                return s;
            }
            if let Some(src) = direct.resolve(name) {
                id.insert(name.clone(), g.names.len());
                g.direct.push((g.names.len(), src));
                g.names.push(name.clone());
                g.producer.push(None);
                return g.names.len() - 1;
            }
            if let Some(src) = ReactionSource::resolve(name, &joints, direct.coordinates) {
                id.insert(name.clone(), g.names.len());
                g.reactions.push((g.names.len(), src));
                g.names.push(name.clone());
                g.producer.push(None);
                return g.names.len() - 1;
            }
            if let Some(what) = name.strip_prefix("output:") {
                let lists = output_names.get_or_insert_with(|| {
                    elements
                        .iter()
                        .map(|e| {
                            e.output_names()
                                .into_iter()
                                .map(|(o, _)| format!("{}.{o}", e.name()))
                                .collect()
                        })
                        .collect()
                });
                let found = lists
                    .iter()
                    .enumerate()
                    .find_map(|(k, l)| l.iter().position(|n| n == what).map(|o| (k, o)));
                if let Some((k, o)) = found {
                    let s = g.names.len();
                    id.insert(name.clone(), s);
                    g.names.push(name.clone());
                    g.producer.push(Some((
                        k,
                        elements[k].signal_outputs().len() + g.probe_ids[k].len(),
                    )));
                    g.probe_outputs[k].push(o);
                    g.probe_counts[k] = lists[k].len();
                    g.probe_ids[k].push(s);
                    return s;
                }
            }
            g.issues.push(SignalIssue::Unknown {
                consumer: consumer.to_string(),
                signal: name.clone(),
            });
            id.insert(name.clone(), g.names.len());
            g.names.push(name.clone());
            g.producer.push(None);
            g.names.len() - 1
        };
        for e in elements {
            let ids = e
                .signal_inputs()
                .iter()
                .map(|n| resolve(&mut g, e.name(), n))
                .collect();
            g.element_inputs.push(ids);
        }
        for (name, inputs) in constraint_inputs {
            let ids = inputs.iter().map(|n| resolve(&mut g, name, n)).collect();
            g.constraint_inputs.push(ids);
        }
        g.order_producers(elements);
        // Supports in evaluation order.
        let ns = g.names.len();
        g.support = vec![Vec::new(); ns];
        g.local_pos = vec![Vec::new(); ns];
        g.input_pos = vec![Vec::new(); ns];
        for &(s, src) in &g.direct {
            g.support[s] = vec![src.config];
        }
        g.n_held += g.reactions.len();
        for &k in &g.order.clone() {
            let outs = elements[k].signal_outputs().len();
            let probed = g.probe_ids[k].clone();
            for o in 0..outs + probed.len() {
                let s = if o < outs {
                    let Some(s) = g.id_of(k, o) else { continue };
                    s
                } else {
                    probed[o - outs]
                };
                let mut sup: Vec<ConfigIndex> = local_config[k].clone();
                for &j in &g.element_inputs[k] {
                    sup.extend_from_slice(&g.support[j]);
                }
                sup.sort_unstable();
                sup.dedup();
                let pos = |c: &ConfigIndex| sup.binary_search(c).unwrap_or(usize::MAX);
                g.local_pos[s] = local_config[k].iter().map(pos).collect();
                g.input_pos[s] = g.element_inputs[k]
                    .iter()
                    .map(|&j| g.support[j].iter().map(pos).collect())
                    .collect();
                g.support[s] = sup;
            }
        }
        g
    }

    fn id_of(&self, element: usize, output: usize) -> Option<usize> {
        self.element_outputs[element][output]
    }

    /// Whether element `k` produces signals (its own or probed outputs).
    fn produces(&self, elements: &[Box<dyn Element>], k: usize) -> bool {
        !elements[k].signal_outputs().is_empty() || !self.probe_ids[k].is_empty()
    }

    /// Number of values held in [`State::held`]: the elements' and the reactions'.
    pub fn n_held(&self) -> usize {
        self.n_held
    }

    /// Topological order of the producers over feedthrough edges (Kahn); the elements of a
    /// loop are appended at the end and the loop is reported.
    fn order_producers(&mut self, elements: &[Box<dyn Element>]) {
        let producers: Vec<usize> = (0..elements.len())
            .filter(|&k| self.produces(elements, k))
            .collect();
        // An edge p → k when k has feedthrough and reads an output of p.
        let mut indegree = vec![0usize; elements.len()];
        let mut next: Vec<Vec<usize>> = vec![Vec::new(); elements.len()];
        for &k in &producers {
            // An output is a function of everything the element sees, its inputs too.
            if !elements[k].feedthrough() && self.probe_ids[k].is_empty() {
                continue;
            }
            for &s in &self.element_inputs[k] {
                if let Some((p, _)) = self.producer[s]
                    && self.produces(elements, p)
                {
                    next[p].push(k);
                    indegree[k] += 1;
                }
            }
        }
        let mut ready: Vec<usize> = producers
            .iter()
            .copied()
            .filter(|&k| indegree[k] == 0)
            .rev()
            .collect();
        let mut done = vec![false; elements.len()];
        while let Some(p) = ready.pop() {
            self.order.push(p);
            done[p] = true;
            for &k in &next[p] {
                indegree[k] -= 1;
                if indegree[k] == 0 {
                    ready.push(k);
                }
            }
        }
        let stuck: Vec<usize> = producers.into_iter().filter(|&k| !done[k]).collect();
        if !stuck.is_empty() {
            let signals = stuck
                .iter()
                .flat_map(|&k| {
                    let probed = self.probe_ids[k].iter().map(|&s| self.names[s].clone());
                    elements[k].signal_outputs().iter().cloned().chain(probed)
                })
                .collect();
            self.issues.push(SignalIssue::Loop { signals });
            self.order.extend(stuck);
        }
    }

    /// Scratch for [`SignalGraph::evaluate`].
    pub fn values(&self, elements: &[Box<dyn Element>]) -> SignalValues {
        let mut terms: Vec<Option<SignalTerms>> = (0..elements.len()).map(|_| None).collect();
        let mut probe_terms: Vec<Option<SignalTerms>> = (0..elements.len()).map(|_| None).collect();
        for &k in &self.order {
            let e = elements[k].as_ref();
            if !e.signal_outputs().is_empty() {
                terms[k] = Some(SignalTerms::for_element(e));
            }
            let rows = self.probe_ids[k].len();
            if rows > 0 {
                let (n, i) = (6 * e.nodes().len() + e.n_states(), e.signal_inputs().len());
                probe_terms[k] = Some(SignalTerms {
                    values: vec![0.0; rows],
                    k: nalgebra::DMatrix::zeros(rows, n),
                    c: nalgebra::DMatrix::zeros(rows, n),
                    m: nalgebra::DMatrix::zeros(rows, n),
                    ds: nalgebra::DMatrix::zeros(rows, i),
                });
            }
        }
        SignalValues {
            values: vec![0.0; self.names.len()],
            gradients: self
                .support
                .iter()
                .map(|s| vec![[0.0; 3]; s.len()])
                .collect(),
            terms,
            probe_terms,
            probe_work: ProbeWork::default(),
            inputs: Vec::new(),
        }
    }

    /// Values (and, with `gradients`, derivatives) of every signal at `state`;
    /// `state_offsets[k]` is where element k's states start in `state.states`.
    pub fn evaluate(
        &self,
        elements: &[Box<dyn Element>],
        state_offsets: &[usize],
        ctx: &EvalContext,
        state: &State,
        out: &mut SignalValues,
        gradients: bool,
    ) {
        for &(s, src) in &self.direct {
            out.values[s] = if src.coordinate {
                let c = &state.coords[src.index];
                [c.q, c.v, c.a][src.channel]
            } else {
                let z = &state.states[src.index];
                [z.z, z.zd][src.channel]
            };
            if gradients {
                let mut g = [0.0; 3];
                g[src.channel] = 1.0;
                out.gradients[s][0] = g;
            }
        }
        let first_reaction = self.n_held - self.reactions.len();
        for (i, &(s, _)) in self.reactions.iter().enumerate() {
            // Held (dynamics); nothing is held in statics, where no reaction sensor runs.
            out.values[s] = if state.held.len() == self.n_held {
                state.held[first_reaction + i]
            } else {
                0.0
            };
        }
        for &k in &self.order {
            let e = elements[k].as_ref();
            out.inputs.clear();
            out.inputs
                .extend(self.element_inputs[k].iter().map(|&j| out.values[j]));
            let off = state_offsets[k];
            let x = ElementInput {
                nodes: &state.nodes,
                states: &state.states[off..off + e.n_states()],
                signals: &out.inputs,
                held: if state.held.len() == self.n_held && self.n_held > 0 {
                    let o = self.held_offsets[k];
                    &state.held[o..o + e.n_held()]
                } else {
                    &[]
                },
            };
            if let Some(t) = out.terms[k].as_mut() {
                t.clear();
                e.signals(ctx, &x, t);
                for o in 0..t.values.len() {
                    let Some(s) = self.id_of(k, o) else { continue };
                    self.chain(k, s, o, t, &mut out.values, &mut out.gradients, gradients);
                }
            }
            if let Some(t) = out.probe_terms[k].as_mut() {
                t.clear();
                let which = (self.probe_outputs[k].as_slice(), self.probe_counts[k]);
                output_terms(e, ctx, &x, which, gradients, &mut out.probe_work, t);
                for (o, &s) in self.probe_ids[k].iter().enumerate() {
                    self.chain(k, s, o, t, &mut out.values, &mut out.gradients, gradients);
                }
            }
        }
    }

    /// Stores row `o` of producer `k`'s terms `t` as signal `s`: its value and (with
    /// `with_gradients`) its derivatives over its support by the chain rule.
    #[allow(clippy::too_many_arguments)]
    fn chain(
        &self,
        k: usize,
        s: usize,
        o: usize,
        t: &SignalTerms,
        values: &mut [f64],
        gradients: &mut [Vec<[f64; 3]>],
        with_gradients: bool,
    ) {
        values[s] = t.values[o];
        if !with_gradients {
            return;
        }
        let mut g = std::mem::take(&mut gradients[s]);
        g.iter_mut().for_each(|x| *x = [0.0; 3]);
        for (l, &p) in self.local_pos[s].iter().enumerate() {
            g[p][0] += t.k[(o, l)];
            g[p][1] += t.c[(o, l)];
            g[p][2] += t.m[(o, l)];
        }
        for (j, &sj) in self.element_inputs[k].iter().enumerate() {
            let d = t.ds[(o, j)];
            if d == 0.0 {
                continue;
            }
            for (gi, &p) in gradients[sj].iter().zip(&self.input_pos[s][j]) {
                for c in 0..3 {
                    g[p][c] += d * gi[c];
                }
            }
        }
        gradients[s] = g;
    }
}

impl SignalGraph {
    /// Explicit time derivatives `[∂s/∂t, ∂²s/∂t²]` of every signal, after
    /// [`SignalGraph::evaluate`] into `values` at the same state and time: each producer's
    /// own ([`Element::signal_time_derivatives`]) plus the chain through its inputs,
    /// `Σ_j (∂g/∂s_j) ∂s_j/∂t` (for the second derivative this leaves out the curvature
    /// of nonlinear blocks: exact through linear ones). Signals read straight from the
    /// unknowns have none. For the consistent initial conditions (allocates).
    pub fn time_derivatives(
        &self,
        elements: &[Box<dyn Element>],
        ctx: &EvalContext,
        values: &SignalValues,
    ) -> Vec<[f64; 2]> {
        let mut out = vec![[0.0; 2]; self.names.len()];
        for &k in &self.order {
            let e = elements[k].as_ref();
            let n_out = e.signal_outputs().len();
            let mut own = vec![[0.0; 2]; n_out];
            e.signal_time_derivatives(ctx, &mut own);
            let Some(t) = values.terms[k].as_ref() else {
                continue;
            };
            for (o, d) in own.iter_mut().enumerate() {
                for (j, &sj) in self.element_inputs[k].iter().enumerate() {
                    let ds = t.ds[(o, j)];
                    d[0] += ds * out[sj][0];
                    d[1] += ds * out[sj][1];
                }
                if let Some(s) = self.id_of(k, o) {
                    out[s] = *d;
                }
            }
        }
        out
    }
}
