//! Figures: SVG text content, PNG decoding, size and non-trivial content, input errors.

mod common;

use indentify_report::{Figure, FigureSize, ReportError};

const SMALL: FigureSize = FigureSize {
    width: 480,
    height: 320,
};

/// Every SVG figure shall carry its axis labels (with units) and its legend entries.
#[test]
fn svg_has_axis_labels_and_legend() {
    let r = common::nano_report();
    let svg = r.figure_svg(Figure::ForceDepth, SMALL).unwrap();
    assert!(svg.starts_with("<svg"));
    for text in [
        "depth h [nm]",
        "force F [mN]",
        "data",
        "fit, start parameters",
        "fit, identified parameters",
    ] {
        assert!(svg.contains(text), "force-depth SVG lacks {text:?}");
    }
    let svg = r.figure_svg(Figure::ForceTime, SMALL).unwrap();
    for text in ["time t [s]", "force F [mN]", "fit, identified parameters"] {
        assert!(svg.contains(text), "force-time SVG lacks {text:?}");
    }
    let svg = r.figure_svg(Figure::Convergence, SMALL).unwrap();
    for text in [
        "iteration",
        "cost J",
        "parameter / final value",
        "E / E_final",
        "eta / eta_final",
    ] {
        assert!(svg.contains(text), "convergence SVG lacks {text:?}");
    }
    // nu is fixed: no history line for it.
    assert!(!svg.contains("nu / nu_final"));
}

/// A macroscopic test shall be plotted in mm and N.
#[test]
fn macro_svg_uses_mm_and_newton() {
    let svg = common::macro_report()
        .figure_svg(Figure::ForceDepth, SMALL)
        .unwrap();
    assert!(svg.contains("depth h [mm]"));
    assert!(svg.contains("force F [N]"));
}

/// Each PNG shall decode to the requested size and not be a single color.
#[test]
fn png_decodes_with_right_size_and_content() {
    let r = common::nano_report();
    for fig in Figure::ALL {
        let bytes = r.figure_png(fig, SMALL).unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (SMALL.width, SMALL.height));
        let pixels = &buf[..info.buffer_size()];
        let px = info.color_type.samples();
        let first = &pixels[..px];
        let differing = pixels.chunks(px).filter(|p| *p != first).count();
        assert!(
            differing > 1000,
            "{fig:?}: only {differing} pixels differ from the first"
        );
        // Red (the identified fit) is present.
        assert!(
            pixels
                .chunks(px)
                .any(|p| p[0] > 180 && p[1] < 80 && p[2] < 80),
            "{fig:?}: no red pixel"
        );
    }
}

/// Non-finite points shall be skipped; a series with none left shall be an error.
#[test]
fn non_finite_points_are_skipped_and_all_nan_is_an_error() {
    let mut r = common::nano_report();
    r.curves.f_data[3] = f64::NAN;
    r.curves.f_final[5] = f64::INFINITY;
    r.figure_svg(Figure::ForceDepth, SMALL).unwrap();
    r.history[1].cost = f64::NAN;
    r.figure_svg(Figure::Convergence, SMALL).unwrap();

    r.curves.f_data.iter_mut().for_each(|f| *f = f64::NAN);
    assert!(matches!(
        r.figure_svg(Figure::ForceTime, SMALL),
        Err(ReportError::Empty {
            what: "curves.f_data"
        })
    ));
    r.history.clear();
    assert!(matches!(
        r.figure_png(Figure::Convergence, SMALL),
        Err(ReportError::Empty { .. })
    ));
}

/// Mismatched lengths and absurd sizes shall be errors, not panics.
#[test]
fn bad_lengths_and_sizes_are_errors() {
    let mut r = common::nano_report();
    r.curves.f_final.pop();
    assert!(matches!(
        r.figure_png(Figure::ForceDepth, SMALL),
        Err(ReportError::Length { .. })
    ));
    let r = common::nano_report();
    assert!(matches!(
        r.figure_png(
            Figure::ForceDepth,
            FigureSize {
                width: 0,
                height: 300
            }
        ),
        Err(ReportError::Size { .. })
    ));
}

/// Without a start curve or free parameters the figures shall still draw.
#[test]
fn optional_parts_may_be_missing() {
    let mut r = common::nano_report();
    r.curves.f_start = None;
    let svg = r.figure_svg(Figure::ForceDepth, SMALL).unwrap();
    assert!(!svg.contains("fit, start parameters"));
    r.parameters.iter_mut().for_each(|p| p.fixed = true);
    let svg = r.figure_svg(Figure::Convergence, SMALL).unwrap();
    assert!(svg.contains("cost J"));
    assert!(!svg.contains("parameter / final value"));
    // Constant cost: the log axis still gets a decade.
    r.history.iter_mut().for_each(|h| h.cost = 2.0);
    r.figure_png(Figure::Convergence, SMALL).unwrap();
}

/// The force figures carry the identified values, the fit's numbers and the source in
/// their header; force-time has a residual panel; the start curve's swatch is dashed.
#[test]
fn force_figures_state_the_result_and_the_residuals() {
    let r = common::nano_report();
    let free: Vec<_> = r.parameters.iter().filter(|p| !p.fixed).collect();
    assert!(!free.is_empty());
    for figure in [Figure::ForceDepth, Figure::ForceTime] {
        let svg = r.figure_svg(figure, SMALL).unwrap();
        assert!(svg.contains("identified: "), "{figure:?} lacks the values");
        for p in &free {
            assert!(
                svg.contains(&format!("{} = ", p.name)),
                "{figure:?} lacks {}",
                p.name
            );
        }
        assert!(svg.contains("RMS residual"), "{figure:?} lacks the RMS");
        assert!(svg.contains("stroke-dasharray") || svg.matches("<polyline").count() > 3);
    }
    let svg = r.figure_svg(Figure::ForceTime, SMALL).unwrap();
    assert!(
        svg.contains("fit - data [mN]"),
        "force-time lacks the residual panel"
    );
    let svg = r.figure_svg(Figure::ForceDepth, SMALL).unwrap();
    assert!(
        !svg.contains("fit - data"),
        "force-depth has no residual panel"
    );
}

/// A figure pasted alone carries the console's verdict: ± σ beside each identified value,
/// `undetermined` instead of a deviation, `last iterate (NOT converged)`, and a CAVEAT line
/// for systematic residuals and for a discretization shift beyond σ.
#[test]
fn figure_headers_carry_the_verdict() {
    use indentify_report::{
        Adequacy, DiscretizationSummary, IdentifiabilitySummary, Undetermined, Verdict,
    };
    let r = common::nano_report();
    let svg = r
        .figure_svg(Figure::ForceDepth, FigureSize::default())
        .unwrap();
    // a converged fit: its values with their deviations (E 201.3 GPa, σ 2.1 GPa)
    assert!(svg.contains("identified: E = 201.3 ± 2.1 GPa"), "{svg}");
    assert!(svg.contains("eta at its upper bound"), "{svg}");

    let mut r = common::nano_report();
    r.convergence.converged = Some(false);
    r.identifiability = Some(IdentifiabilitySummary {
        names: vec!["E".into(), "eta".into()],
        singular_values: vec![1.0, 1e-9],
        directions: vec![vec![1.0, 0.0], vec![0.0, 1.0]],
        condition: "1e18".into(),
        weakest: None,
        undetermined: vec![Undetermined {
            name: "eta".into(),
            reason: "flat".into(),
        }],
        advice: String::new(),
    });
    // a refined mesh moves E by 5 GPa = 2.4 σ
    r.discretization = Some(DiscretizationSummary {
        refined: "2x".into(),
        rms_rel: 1e-3,
        max_abs: 1e-5,
        shift: vec![Some(5e3), None, None],
        seconds: 1.0,
    });
    let c = &r.curves;
    let mut a = Adequacy::assess(&c.t, &c.f_data, &c.f_final, 2).unwrap();
    a.verdict = Verdict::Systematic;
    r.adequacy = Some(a);
    for fig in [Figure::ForceDepth, Figure::ForceTime] {
        // the header's text, its wrapped lines joined again
        let svg: String = r
            .figure_svg(fig, FigureSize::default())
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('<'))
            .collect::<Vec<_>>()
            .join(" ");
        for text in [
            "last iterate (NOT converged): E = 201.3 ± 2.1 GPa",
            "eta = 5000 GPa s undetermined",
            "CAVEAT: NOT converged",
            "systematic residuals",
            "discretization error beyond σ: a refined mesh moves E by 2.4 σ",
            "undetermined: eta",
        ] {
            assert!(svg.contains(text), "{fig:?}: no `{text}` in {svg}");
        }
        // no deviation shown for the undetermined parameter
        assert!(!svg.contains("5000 ±"), "{svg}");
    }
}
