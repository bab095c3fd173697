//! Small fixed reports shared by the integration tests.

use indentify_report::{
    BoundHit, Convergence, Correlation, Curves, DisplayUnit, FigureLink, FitQuality,
    IterationRecord, NameValue, Parameter, PreprocessingStep, Report, Source,
};

/// A Maxwell nano-indentation: 2 µm deep, about 10 mN, 21 points (load, hold, unload).
pub fn nano_report() -> Report {
    let n = 21;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.5).collect();
    // Depth ramps to 2e-3 mm in 4 s, holds 2 s, unloads to 1.5e-3 mm.
    let h: Vec<f64> = t
        .iter()
        .map(|&t| {
            if t <= 4.0 {
                2e-3 * t / 4.0
            } else if t <= 6.0 {
                2e-3
            } else {
                2e-3 - 0.5e-3 * (t - 6.0) / 4.0
            }
        })
        .collect();
    let f_model = |e: f64, relax: f64| -> Vec<f64> {
        h.iter()
            .zip(&t)
            .map(|(&h, &t)| {
                let hold = if t > 4.0 {
                    (-(t - 4.0) * relax).exp()
                } else {
                    1.0
                };
                e * 2.5e3 * h * h * hold
            })
            .collect()
    };
    let f_final = f_model(1.0, 0.05);
    let f_start = f_model(0.7, 0.2);
    let f_data: Vec<f64> = f_final
        .iter()
        .enumerate()
        .map(|(i, f)| f * (1.0 + 0.01 * ((i * 7 % 5) as f64 - 2.0)))
        .collect();
    let fit = FitQuality::compute(&f_data, &f_final).unwrap();
    let gpa = DisplayUnit::new("GPa", 1e-3);
    let params = vec![
        Parameter {
            name: "E".into(),
            unit: gpa.clone(),
            start: 150e3,
            value: 201.3e3,
            lower: Some(1e3),
            upper: Some(1e6),
            at_bound: None,
            fixed: false,
            std_dev: Some(2.1e3),
        },
        Parameter {
            name: "nu".into(),
            unit: DisplayUnit::internal("-"),
            start: 0.3,
            value: 0.3,
            lower: None,
            upper: None,
            at_bound: None,
            fixed: true,
            std_dev: None,
        },
        Parameter {
            name: "eta".into(),
            unit: DisplayUnit::new("GPa s", 1e-3),
            start: 1e6,
            value: 5e6,
            lower: Some(1e4),
            upper: Some(5e6),
            at_bound: Some(BoundHit::Upper),
            fixed: false,
            std_dev: Some(0.4e6),
        },
    ];
    let history = (0..4)
        .map(|k| {
            let w = k as f64 / 3.0;
            IterationRecord {
                iteration: k,
                cost: 1e-4 * 10f64.powi(-2 * k as i32),
                grad_norm: Some(3.0 * 10f64.powi(-(k as i32))),
                params: vec![150e3 + w * 51.3e3, 0.3, 1e6 + (5e6 - 1e6) * w.sqrt()],
            }
        })
        .collect();
    Report {
        title: "Maxwell identification, fused silica test 3".into(),
        source: Source {
            file: "data/silica.csv".into(),
            test: "3".into(),
            metadata: vec![
                NameValue::new("instrument", "NanoTest Vantage"),
                NameValue::new("tip", "Berkovich (conical equivalent 70.3°)"),
            ],
        },
        law: "maxwell".into(),
        parameters: params,
        correlation: Some(Correlation {
            names: vec!["E".into(), "eta".into()],
            matrix: vec![vec![1.0, -0.62], vec![-0.62, 1.0]],
        }),
        convergence: Convergence {
            stop_reason: "projected gradient below 1e-8".into(),
            iterations: 3,
            forward_solves: 5,
            adjoint_solves: 4,
            wall_time_s: 12.5,
            converged: Some(true),
        },
        fit,
        preprocessing: vec![
            PreprocessingStep::new("zero point", "h shifted by -12.3 nm at F = 0.05 mN"),
            PreprocessingStep::new("resample", "21 points, uniform in time"),
        ],
        curves: Curves::with_auto_units(t, h, f_data, Some(f_start), f_final),
        history,
        figures: vec![
            FigureLink::new("force-depth", "fig/force_depth.svg"),
            FigureLink::new("convergence", "fig/convergence.svg"),
        ],
        warnings: Vec::new(),
        discretization: None,
        identifiability: None,
        adequacy: None,
    }
}

/// A macroscopic test: 0.1 mm deep, about 300 N.
pub fn macro_report() -> Report {
    let mut r = nano_report();
    let scale_h = 0.1 / 2e-3;
    let scale_f = 300.0 / 10e-3;
    let c = &r.curves;
    let h = c.h.iter().map(|h| h * scale_h).collect();
    let fd: Vec<f64> = c.f_data.iter().map(|f| f * scale_f).collect();
    let ff: Vec<f64> = c.f_final.iter().map(|f| f * scale_f).collect();
    let fs = c
        .f_start
        .as_ref()
        .map(|v| v.iter().map(|f| f * scale_f).collect());
    r.fit = FitQuality::compute(&fd, &ff).unwrap();
    r.curves = Curves::with_auto_units(c.t.clone(), h, fd, fs, ff);
    r.title = "Maxwell identification, steel, macro test".into();
    r
}
