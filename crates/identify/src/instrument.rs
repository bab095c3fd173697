//! Instrument (nuisance) parameters identified beside the law's (docs/theory.md §13.6):
//! the frame compliance `Cf` (mm/N), the thermal drift rate `vd` (mm/s) and a depth offset
//! `h0` per test (mm, the zero point's error). Under load control the measured depth of
//! test `k` at schedule time `t_i` is
//!
//! `h_meas,i = h_i(c) + Cf F_i(c) + vd (t_i - t_0) + h0_k`,
//!
//! with `h_i` the punch depth the model solves, `F_i` its force (the prescribed `P(t_i)` on
//! load-controlled steps) and `t_0` the test's first schedule time (the record's start).
//! The terms are additive, so their derivatives are exact and cheap: `dh_meas/dCf = F_i`,
//! `dh_meas/dvd = t_i - t_0`, `dh_meas/dh0_k = 1`, and the law's columns gain
//! `Cf dF_i/dc` (non-zero on depth-controlled steps only).
//!
//! The pieces:
//! - [`Instrument`]: which of the three a problem identifies.
//! - [`Instrumented`]: a [`Material`] whose parameter list is the law's followed by the
//!   instrument's (`Cf`, `vd`, then `h0` for one test or `h0[1]`, `h0[2]`, ... for a joint
//!   problem); it forwards every call to the law with the law's part of `c` (the
//!   instrument's columns of the parameter derivatives are zero: the instrument does not
//!   touch the material). The [`crate::Parameterization`], the optimizers, the
//!   identifiability and every report see the instrument's parameters through it.
//! - `Applied` (crate-private): what a [`crate::Problem`]'s evaluator adds to a test's
//!   observables, its adjoint gradient and its sensitivity rows.
//!
//! Depth-controlled tests (the force is the observable) run through the frame instead
//! (docs/theory.md §13.7): the recorded depth is the machine's, so the punch is driven
//! through the frame's spring towards `H(t) = h_rec(t) - vd (t - t0) - h0_k`
//! (`DirectSolver::run_compliant`), the observable stays the force, and the gradient and
//! sensitivities with respect to `Cf`, `vd` and `h0_k` come from the compliant adjoint
//! (`Adjoint::gradient_compliant`, `Adjoint::sensitivities_compliant`).

use std::sync::{Arc, Mutex, OnceLock};

use indentify_adjoint::{FrameIndex, LoadReplay};
use indentify_contact::{Frame, Trajectory};
use indentify_laws::{
    ElasticDomain, InternalInfo, Law, LawError, LocalFailure, LocalUpdate, Mat4, Material,
    MaterialUpdate, ParamInfo, Step, Vec4, material::check_param_ranges,
};

use crate::IdentifyError;
use crate::problem::{Problem, Test, Work, in_full};

/// Name of the frame compliance.
pub const COMPLIANCE: &str = "Cf";
/// Name of the thermal drift rate.
pub const DRIFT: &str = "vd";
/// Name of the depth offset (of every test: `h0[k]` names test `k`, 1-based, in a joint
/// problem).
pub const OFFSET: &str = "h0";

/// Which instrument parameters a problem carries (each is free or fixed as its
/// [`crate::ParamSpec`] says; a parameter not carried is 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Instrument {
    /// The frame compliance `Cf` (mm/N, >= 0), shared by every test.
    pub compliance: bool,
    /// The thermal drift rate `vd` (mm/s, any sign), shared by every test.
    pub drift: bool,
    /// A depth offset `h0` (mm, any sign) per test.
    pub offset: bool,
}

impl Instrument {
    /// Whether it carries no parameter.
    pub fn is_empty(&self) -> bool {
        !(self.compliance || self.drift || self.offset)
    }

    /// Whether `name` is an instrument parameter's name (`Cf`, `vd`, `h0`, `h0[k]`).
    pub fn is_name(name: &str) -> bool {
        name == COMPLIANCE || name == DRIFT || Instrument::offset_test(name).is_some()
    }

    /// The test a name of the offset refers to: `Some(None)` for `h0` (every test),
    /// `Some(Some(k))` for `h0[k]` (1-based as written), `None` for another name.
    pub fn offset_test(name: &str) -> Option<Option<usize>> {
        if name == OFFSET {
            return Some(None);
        }
        let inner = name.strip_prefix("h0[")?.strip_suffix(']')?;
        inner.parse::<usize>().ok().filter(|&k| k >= 1).map(Some)
    }

    /// The parameter names it adds after the law's, for a problem of `n_tests` tests.
    pub fn names(&self, n_tests: usize) -> Vec<&'static str> {
        self.entries(n_tests).iter().map(|e| e.name()).collect()
    }

    /// The entries in parameter order.
    fn entries(&self, n_tests: usize) -> Vec<Entry> {
        let mut out = Vec::new();
        if self.compliance {
            out.push(Entry::Compliance);
        }
        if self.drift {
            out.push(Entry::Drift);
        }
        if self.offset {
            if n_tests == 1 {
                out.push(Entry::Offset {
                    test: 0,
                    joint: false,
                });
            } else {
                out.extend((0..n_tests).map(|test| Entry::Offset { test, joint: true }));
            }
        }
        out
    }

    /// The scale of the `Linear` scaling of an instrument parameter that starts at 0
    /// (the start is the scale otherwise): 1e-4 mm/N (0.1 nm/mN) for `Cf`, 1e-6 mm/s (1
    /// nm/s) for `vd`, 1e-4 mm (0.1 um) for `h0`; `None` for another name.
    pub fn nominal_scale(name: &str) -> Option<f64> {
        if name == COMPLIANCE {
            Some(1e-4)
        } else if name == DRIFT {
            Some(1e-6)
        } else if Instrument::offset_test(name).is_some() {
            Some(1e-4)
        } else {
            None
        }
    }
}

/// One instrument parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Entry {
    Compliance,
    Drift,
    /// Test `test`'s offset (0-based); `joint`: named `h0[test + 1]`.
    Offset {
        test: usize,
        joint: bool,
    },
}

impl Entry {
    fn name(self) -> &'static str {
        match self {
            Entry::Compliance => COMPLIANCE,
            Entry::Drift => DRIFT,
            Entry::Offset { joint: false, .. } => OFFSET,
            Entry::Offset { test, joint: true } => offset_name(test),
        }
    }

    fn info(self) -> ParamInfo {
        match self {
            Entry::Compliance => ParamInfo {
                name: COMPLIANCE,
                unit: "mm/N",
                description: "frame compliance: the measured depth gains Cf P (instrument)",
                min: 0.0,
                min_inclusive: true,
                max: f64::INFINITY,
                max_inclusive: false,
            },
            Entry::Drift => ParamInfo {
                name: DRIFT,
                unit: "mm/s",
                description: "thermal drift rate: the measured depth gains vd (t - t0), t0 the \
                              record's start (instrument)",
                min: f64::NEG_INFINITY,
                min_inclusive: false,
                max: f64::INFINITY,
                max_inclusive: false,
            },
            Entry::Offset { .. } => ParamInfo {
                name: self.name(),
                unit: "mm",
                description: "depth offset of one test (its zero point's error): the measured \
                              depth gains h0 (instrument)",
                min: f64::NEG_INFINITY,
                min_inclusive: false,
                max: f64::INFINITY,
                max_inclusive: false,
            },
        }
    }
}

/// `h0[k + 1]` as a `&'static str`, interned (one leak per test index ever named).
fn offset_name(k: usize) -> &'static str {
    static NAMES: OnceLock<Mutex<Vec<&'static str>>> = OnceLock::new();
    let mut names = NAMES
        .get_or_init(|| Mutex::new(Vec::new()))
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    while names.len() <= k {
        let i = names.len() + 1;
        names.push(Box::leak(format!("{OFFSET}[{i}]").into_boxed_str()));
    }
    names[k]
}

/// A parameter list as a `&'static` slice, interned (one leak per distinct list: a law
/// with a given instrument and number of tests), for [`Law::params`].
fn static_infos(infos: &[ParamInfo]) -> &'static [ParamInfo] {
    static LISTS: OnceLock<Mutex<Vec<&'static [ParamInfo]>>> = OnceLock::new();
    let mut lists = LISTS
        .get_or_init(|| Mutex::new(Vec::new()))
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(l) = lists.iter().find(|l| **l == infos) {
        return l;
    }
    let l: &'static [ParamInfo] = Box::leak(infos.to_vec().into_boxed_slice());
    lists.push(l);
    l
}

/// A law with the instrument's parameters appended to its own (see the module): the
/// material every consumer of a [`crate::Problem`]'s parameter list sees. Runs through it
/// are the law's runs at the law's part of `c`.
#[derive(Debug)]
pub struct Instrumented {
    inner: Arc<dyn Material>,
    instrument: Instrument,
    n_tests: usize,
    n_law: usize,
    infos: &'static [ParamInfo],
    sliced: Option<SlicedLaw>,
}

impl Instrumented {
    /// `inner` followed by the parameters of `instrument` for `n_tests` tests.
    pub fn new(inner: Arc<dyn Material>, instrument: Instrument, n_tests: usize) -> Instrumented {
        let mut infos: Vec<ParamInfo> = inner.params().to_vec();
        let n_law = infos.len();
        infos.extend(instrument.entries(n_tests).iter().map(|e| e.info()));
        let infos = static_infos(&infos);
        let sliced = inner.as_law().map(|_| SlicedLaw {
            inner: inner.clone(),
            n_law,
            infos,
        });
        Instrumented {
            inner,
            instrument,
            n_tests,
            n_law,
            infos,
            sliced,
        }
    }

    /// The law's own material.
    pub fn law(&self) -> &Arc<dyn Material> {
        &self.inner
    }

    /// The instrument.
    pub fn instrument(&self) -> Instrument {
        self.instrument
    }

    /// The number of the law's own parameters (the instrument's follow).
    pub fn n_law(&self) -> usize {
        self.n_law
    }

    /// The evaluator's view: where each instrument parameter sits in `c`.
    pub(crate) fn applied(&self) -> Applied {
        let mut a = Applied {
            n_law: self.n_law,
            n_all: self.infos.len(),
            compliance: None,
            drift: None,
            offsets: vec![None; self.n_tests],
        };
        for (j, e) in self.instrument.entries(self.n_tests).iter().enumerate() {
            let at = self.n_law + j;
            match *e {
                Entry::Compliance => a.compliance = Some(at),
                Entry::Drift => a.drift = Some(at),
                Entry::Offset { test, .. } => a.offsets[test] = Some(at),
            }
        }
        a
    }
}

/// The instrument's rows (for each row of the given observables) of a problem's test:
/// where its parameters sit in `c`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Applied {
    /// The law's parameters are `c[..n_law]`.
    pub n_law: usize,
    /// `c.len()`.
    pub n_all: usize,
    compliance: Option<usize>,
    drift: Option<usize>,
    /// Per test, its `h0`'s index.
    offsets: Vec<Option<usize>>,
}

impl Applied {
    /// `Cf` at `c` (0 when not carried).
    pub fn compliance(&self, c: &[f64]) -> f64 {
        self.compliance.map_or(0.0, |i| c[i])
    }

    /// Test `k`'s frame at `c` (each parameter not carried 0): what a depth-controlled
    /// test's compliant run takes.
    pub fn frame(&self, k: usize, c: &[f64]) -> Frame {
        Frame {
            compliance: self.compliance(c),
            drift: self.drift.map_or(0.0, |i| c[i]),
            offset: self.offsets[k].map_or(0.0, |i| c[i]),
        }
    }

    /// Where test `k`'s frame parameters sit in `c`.
    pub fn frame_index(&self, k: usize) -> FrameIndex {
        FrameIndex {
            compliance: self.compliance,
            drift: self.drift,
            offset: self.offsets[k],
        }
    }

    /// The entries of the frame's gradient `dJ/d(Cf, vd, h0)` of a depth-controlled
    /// test `k` into `g` (the other entries untouched).
    pub fn frame_gradient(&self, k: usize, dj_dframe: [f64; 3], g: &mut [f64]) {
        let at = self.frame_index(k);
        for (i, d) in [at.compliance, at.drift, at.offset]
            .into_iter()
            .zip(dj_dframe)
        {
            if let Some(i) = i {
                g[i] = d;
            }
        }
    }

    /// Adds `Cf F_i + vd (t_i - t_0) + h0_k` to the observables `obs` of test `k` (one per
    /// schedule time, index 0 the initial state) under load control; a depth-controlled
    /// test's observables are its forces, which the frame already shaped.
    pub fn observe(&self, k: usize, test: &Test, c: &[f64], traj: &Trajectory, obs: &mut [f64]) {
        if test.load.is_none() {
            return;
        }
        let forces = traj.forces();
        let t0 = test.schedule.t[0];
        let (cf, vd) = (self.compliance(c), self.drift.map_or(0.0, |i| c[i]));
        let h0 = self.offsets[k].map_or(0.0, |i| c[i]);
        for (j, o) in obs.iter_mut().enumerate() {
            let f = forces.get(j).copied().unwrap_or(0.0);
            *o += cf * f + vd * (test.schedule.t[j] - t0) + h0;
        }
    }

    /// `dJ_k/dc` of the instrument's parameters (the other entries untouched) from the
    /// weighted residuals `r_j = w_j (h_meas,j - h_exp,j)` of test `k` at its schedule
    /// times.
    pub fn gradient(&self, k: usize, test: &Test, traj: &Trajectory, r: &[f64], g: &mut [f64]) {
        let forces = traj.forces();
        let t0 = test.schedule.t[0];
        if let Some(i) = self.compliance {
            g[i] = r.iter().zip(&forces).map(|(r, f)| r * f).sum();
        }
        if let Some(i) = self.drift {
            g[i] = r
                .iter()
                .zip(&test.schedule.t)
                .map(|(r, t)| r * (t - t0))
                .sum();
        }
        if let Some(i) = self.offsets[k] {
            g[i] = r.iter().sum();
        }
    }

    /// The instrument's columns of test `k`'s sensitivity rows (one row per schedule
    /// time, `n_all` columns, the law's first).
    pub fn jacobian(&self, k: usize, test: &Test, traj: &Trajectory, rows: &mut [Vec<f64>]) {
        let forces = traj.forces();
        let t0 = test.schedule.t[0];
        for (j, row) in rows.iter_mut().enumerate() {
            if let Some(i) = self.compliance {
                row[i] = forces.get(j).copied().unwrap_or(0.0);
            }
            if let Some(i) = self.drift {
                row[i] = test.schedule.t[j] - t0;
            }
            if let Some(i) = self.offsets[k] {
                row[i] = 1.0;
            }
        }
    }
}

/// A depth-controlled test `k`'s gradient with the instrument (docs/theory.md §13.7):
/// the compliant adjoint over its run through the frame (`traj`; a checkpointed run's
/// stretches replayed one at a time, `Adjoint::gradient_compliant_replayed`),
/// `dJ/dF_i = w_i (F_i - F_exp,i)`; the law's entries and the frame's.
pub(crate) fn compliant_gradient(
    p: &Problem,
    a: &Applied,
    c: &[f64],
    k: usize,
    w: &mut Work,
    traj: &Trajectory,
) -> Result<Vec<f64>, IdentifyError> {
    let t = &p.tests[k];
    let (cl, frame) = (p.law_part(c), a.frame(k, c));
    let rho = t.dj_df(traj);
    let g = w
        .adjoint
        .gradient_compliant_replayed(
            &**p.material(),
            cl,
            traj,
            (&t.schedule, &frame),
            &rho,
            LoadReplay {
                solver: &mut w.solver,
                opts: &t.solver_options,
            },
        )
        .map_err(|source| IdentifyError::Adjoint {
            params: c.to_vec(),
            source,
        })?;
    let mut full = vec![0.0; c.len()];
    full[..g.dj_dc.len()].copy_from_slice(&g.dj_dc);
    a.frame_gradient(k, g.dj_dframe, &mut full);
    Ok(full)
}

/// A depth-controlled test `k`'s Jacobian rows (`dF/dc` at its schedule times) with the
/// instrument: the compliant forward sensitivities of the instrumented law (its frame
/// columns with zero law derivatives, set by the differentiated spring).
pub(crate) fn compliant_jacobian(
    p: &Problem,
    a: &Applied,
    c: &[f64],
    k: usize,
    w: &mut Work,
    traj: &Trajectory,
) -> Result<Vec<Vec<f64>>, IdentifyError> {
    let t = &p.tests[k];
    let (cl, frame) = (p.law_part(c), a.frame(k, c));
    let mut slot = None;
    let traj = in_full(traj, &t.solver_options, c, &mut slot, |o| {
        w.solver
            .run_compliant(&**p.material(), cl, &t.schedule, &frame, o)
    })?;
    let sens = w
        .adjoint
        .sensitivities_compliant(&*p.law, c, traj, (&t.schedule, &frame), a.frame_index(k))
        .map_err(|source| IdentifyError::Adjoint {
            params: c.to_vec(),
            source,
        })?;
    let mut jac = vec![vec![0.0; c.len()]; t.schedule.t.len()];
    for (s, row) in traj.steps.iter().zip(&sens.df_dc) {
        if s.on_schedule {
            jac[s.schedule_index].clone_from(row);
        }
    }
    Ok(jac)
}

/// Spreads the law's `m x n` parameter block at the head of `out` in place to `m x nc`
/// (zero columns for the instrument's parameters; rows from the last: a row's
/// destination never precedes the sources still to be read).
fn spread_params(out: &mut [f64], m: usize, n: usize, nc: usize) {
    for i in (0..m).rev() {
        for k in (0..n).rev() {
            out[i * nc + k] = out[i * n + k];
        }
        out[i * nc + n..(i + 1) * nc].fill(0.0);
    }
}

impl Material for Instrumented {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn params(&self) -> &[ParamInfo] {
        self.infos
    }
    fn internal(&self) -> &[InternalInfo] {
        self.inner.internal()
    }
    fn n_internal(&self) -> usize {
        self.inner.n_internal()
    }
    fn state_len(&self) -> usize {
        self.inner.state_len()
    }
    fn check_params(&self, c: &[f64]) -> Result<(), LawError> {
        check_param_ranges(self.name(), self.infos, c)?;
        self.inner.check_params(&c[..self.n_law])
    }
    fn check_differentiable(&self, c: &[f64]) -> Result<(), LawError> {
        self.inner
            .check_differentiable(&c[..self.n_law.min(c.len())])
    }
    fn is_linear(&self) -> bool {
        self.inner.is_linear()
    }
    fn as_law(&self) -> Option<&dyn Law> {
        self.sliced.as_ref().map(|s| s as &dyn Law)
    }
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]) {
        self.inner.residual(&c[..self.n_law], step, r);
    }
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_state(&c[..self.n_law], step, out);
    }
    fn jac_previous(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_previous(&c[..self.n_law], step, out);
    }
    fn jac_strain(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_strain(&c[..self.n_law], step, out);
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        let (n, m) = (self.n_law, self.inner.state_len());
        self.inner.jac_params(&c[..n], step, &mut out[..m * n]);
        spread_params(out, m, n, c.len());
    }
    fn jac_blocks(
        &self,
        c: &[f64],
        step: &Step<'_>,
        a: &mut [f64],
        d: &mut [f64],
        e: &mut [f64],
        p: &mut [f64],
    ) {
        let (n, m) = (self.n_law, self.inner.state_len());
        self.inner
            .jac_blocks(&c[..n], step, a, d, e, &mut p[..m * n]);
        spread_params(p, m, n, c.len());
    }
    /// The law's own contraction (its closed form, if it has one): the instrument's
    /// parameters do not enter the residual, so their entries gain nothing.
    fn jac_params_transpose(
        &self,
        c: &[f64],
        step: &Step<'_>,
        mu: &[f64],
        weight: f64,
        scratch: &mut [f64],
        out: &mut [f64],
    ) {
        let n = self.n_law;
        self.inner
            .jac_params_transpose(&c[..n], step, mu, weight, scratch, &mut out[..n]);
    }
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure> {
        self.inner.update(&c[..self.n_law], y0, deps, dt, y1)
    }
}

/// A stress-only law seen with the instrument's parameters appended: every method the
/// law's at `c[..n_law]`, the derivatives with respect to the instrument's parameters
/// zero (the solver's and the adjoint's `Law` paths, with the law's bits).
#[derive(Debug)]
struct SlicedLaw {
    inner: Arc<dyn Material>,
    n_law: usize,
    infos: &'static [ParamInfo],
}

impl SlicedLaw {
    /// The law (always there: a `SlicedLaw` is only made for a material with one).
    fn law(&self) -> Result<&dyn Law, LocalFailure> {
        self.inner.as_law().ok_or_else(|| LocalFailure {
            reason: "the instrumented material lost its stress-only law".into(),
            suggested_dt_factor: 0.5,
        })
    }
}

impl Law for SlicedLaw {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn params(&self) -> &'static [ParamInfo] {
        self.infos
    }
    fn compliance(&self, c: &[f64]) -> Mat4 {
        self.law()
            .map_or(Mat4::ZERO, |l| l.compliance(&c[..self.n_law]))
    }
    fn compliance_derivative(&self, c: &[f64], k: usize) -> Mat4 {
        match self.law() {
            Ok(l) if k < self.n_law => l.compliance_derivative(&c[..self.n_law], k),
            _ => Mat4::ZERO,
        }
    }
    fn flow(&self, c: &[f64], sigma: &Vec4) -> Vec4 {
        self.law()
            .map_or(Vec4::ZERO, |l| l.flow(&c[..self.n_law], sigma))
    }
    fn flow_hessian(&self, c: &[f64], sigma: &Vec4) -> Mat4 {
        self.law()
            .map_or(Mat4::ZERO, |l| l.flow_hessian(&c[..self.n_law], sigma))
    }
    fn flow_param_derivative(&self, c: &[f64], sigma: &Vec4, k: usize) -> Vec4 {
        match self.law() {
            Ok(l) if k < self.n_law => l.flow_param_derivative(&c[..self.n_law], sigma, k),
            _ => Vec4::ZERO,
        }
    }
    fn flow_param_derivatives(&self, c: &[f64], sigma: &Vec4, out: &mut [Vec4]) {
        let n = self.n_law.min(out.len());
        if let Ok(l) = self.law() {
            l.flow_param_derivatives(&c[..self.n_law], sigma, &mut out[..n]);
        }
        out[n..].fill(Vec4::ZERO);
    }
    fn is_linear(&self) -> bool {
        self.law().is_ok_and(|l| l.is_linear())
    }
    fn affine_update(&self, c: &[f64], dt: f64) -> Option<(Mat4, Mat4)> {
        self.law().ok()?.affine_update(&c[..self.n_law], dt)
    }
    fn elastic_domain(&self, c: &[f64], dt: f64) -> Option<ElasticDomain> {
        self.law().ok()?.elastic_domain(&c[..self.n_law], dt)
    }
    fn check_params(&self, c: &[f64]) -> Result<(), LawError> {
        check_param_ranges(self.name(), self.infos, c)?;
        match self.law() {
            Ok(l) => l.check_params(&c[..self.n_law]),
            Err(_) => Ok(()),
        }
    }
    fn check_differentiable(&self, c: &[f64]) -> Result<(), LawError> {
        match self.law() {
            Ok(l) => l.check_differentiable(&c[..self.n_law.min(c.len())]),
            Err(_) => Ok(()),
        }
    }
    fn residual_param_derivative(
        &self,
        c: &[f64],
        s0: &Vec4,
        s1: &Vec4,
        dt: f64,
        k: usize,
    ) -> Vec4 {
        match self.law() {
            Ok(l) if k < self.n_law => l.residual_param_derivative(&c[..self.n_law], s0, s1, dt, k),
            _ => Vec4::ZERO,
        }
    }
    fn residual_param_derivatives(
        &self,
        c: &[f64],
        s0: &Vec4,
        s1: &Vec4,
        dt: f64,
        out: &mut [Vec4],
    ) {
        let n = self.n_law.min(out.len());
        if let Ok(l) = self.law() {
            l.residual_param_derivatives(&c[..self.n_law], s0, s1, dt, &mut out[..n]);
        }
        out[n..].fill(Vec4::ZERO);
    }
    fn tangent(&self, c: &[f64], sigma: &Vec4, dt: f64) -> Result<Mat4, LocalFailure> {
        self.law()?.tangent(&c[..self.n_law], sigma, dt)
    }
    fn update(
        &self,
        c: &[f64],
        s0: &Vec4,
        deps: &Vec4,
        dt: f64,
    ) -> Result<LocalUpdate, LocalFailure> {
        self.law()?.update(&c[..self.n_law], s0, deps, dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_laws::{LawMaterial, Maxwell};

    #[test]
    fn names_and_offsets() {
        let i = Instrument {
            compliance: true,
            drift: true,
            offset: true,
        };
        assert_eq!(i.names(1), ["Cf", "vd", "h0"]);
        assert_eq!(i.names(3), ["Cf", "vd", "h0[1]", "h0[2]", "h0[3]"]);
        assert_eq!(Instrument::offset_test("h0[2]"), Some(Some(2)));
        assert_eq!(Instrument::offset_test("h0"), Some(None));
        assert_eq!(Instrument::offset_test("h0[0]"), None);
        assert!(Instrument::is_name("Cf") && !Instrument::is_name("E"));
    }

    #[test]
    fn the_wrapper_appends_and_forwards() {
        let inner: Arc<dyn Material> = Arc::new(LawMaterial(&Maxwell));
        let i = Instrument {
            compliance: true,
            drift: false,
            offset: true,
        };
        let w = Instrumented::new(inner, i, 2);
        let names: Vec<_> = w.params().iter().map(|p| p.name).collect();
        assert_eq!(names, ["E", "nu", "eta", "Cf", "h0[1]", "h0[2]"]);
        let c = [20000.0, 0.3, 30000.0, 1e-4, -1e-3, 2e-3];
        w.check_params(&c).unwrap();
        let e = w.check_params(&[20000.0, 0.3, 30000.0, -1e-4, 0.0, 0.0]);
        assert!(e.unwrap_err().to_string().contains("Cf"));
        let law = w.as_law().unwrap();
        assert_eq!(law.compliance(&c), Maxwell.compliance(&c[..3]));
        assert_eq!(law.compliance_derivative(&c, 3), Mat4::ZERO);
        // the material path's parameter block: the law's columns, then zeros
        let y0 = [1.0, 2.0, 3.0, 0.5];
        let y1 = [2.0, 1.0, 3.5, 0.25];
        let deps = Vec4([1e-4, 0.0, -1e-4, 0.0]);
        let step = Step {
            y0: &y0,
            y1: &y1,
            deps: &deps,
            dt: 0.1,
            regime: Default::default(),
        };
        let mut a = vec![f64::NAN; 4 * 6];
        w.jac_params(&c, &step, &mut a);
        let mut b = vec![0.0; 4 * 3];
        LawMaterial(&Maxwell).jac_params(&c[..3], &step, &mut b);
        for i in 0..4 {
            assert_eq!(&a[i * 6..i * 6 + 3], &b[i * 3..i * 3 + 3]);
            assert_eq!(&a[i * 6 + 3..i * 6 + 6], &[0.0; 3]);
        }
    }
}
