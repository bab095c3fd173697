//! Renders the test reports (nano and macro) to a directory: `cargo run -p indentify-report --example render -- /tmp/report`.

#[path = "../tests/common/mod.rs"]
mod common;

use indentify_report::{Figure, FigureSize};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or("/tmp/report".into()));
    std::fs::create_dir_all(&dir)?;
    // Dense noisy data shown in internal units (mm, N): small tick values, line not markers.
    let mut dense = common::nano_report();
    {
        let c = &mut dense.curves;
        let n = 2000;
        let t_end = *c.t.last().unwrap_or(&1.0);
        let interp = |v: &[f64], t: f64| {
            let x = t / t_end * (v.len() - 1) as f64;
            let i = (x.floor() as usize).min(v.len() - 2);
            v[i] + (x - i as f64) * (v[i + 1] - v[i])
        };
        let t: Vec<f64> = (0..n).map(|i| t_end * i as f64 / (n - 1) as f64).collect();
        c.h = t.iter().map(|&s| interp(&c.h, s)).collect();
        c.f_final = t.iter().map(|&s| interp(&c.f_final, s)).collect();
        c.f_start = c
            .f_start
            .as_ref()
            .map(|f| t.iter().map(|&s| interp(f, s)).collect());
        c.f_data = c
            .f_final
            .iter()
            .enumerate()
            .map(|(i, f)| f + 2e-4 * (((i * 7919) % 101) as f64 / 50.0 - 1.0))
            .collect();
        c.t = t;
        c.depth_unit = indentify_report::DisplayUnit::internal("mm");
        c.force_unit = indentify_report::DisplayUnit::internal("N");
    }
    // A long, non-monotone history (40 iterations, overshooting parameters).
    let mut long = common::nano_report();
    long.history = (0..40)
        .map(|k| {
            let w = (-(k as f64) / 6.0).exp();
            indentify_report::IterationRecord {
                iteration: k,
                cost: 3e-3 * (-(k as f64) / 3.0).exp() * (1.0 + 0.5 * (k as f64).sin().abs()),
                grad_norm: Some(w),
                params: vec![
                    201.3e3 * (1.0 - 0.3 * w * (k as f64 / 2.0).cos()),
                    0.3,
                    5e6 * (1.0 + 1.5 * w * (k as f64 / 3.0).cos()),
                ],
            }
        })
        .collect();
    for (name, report) in [
        ("long", long),
        ("nano", common::nano_report()),
        ("macro", common::macro_report()),
        ("dense", dense),
    ] {
        std::fs::write(dir.join(format!("{name}.md")), report.to_markdown())?;
        std::fs::write(dir.join(format!("{name}.json")), report.to_json()?)?;
        for fig in Figure::ALL {
            let stem = format!("{name}_{}", fig.file_stem());
            std::fs::write(
                dir.join(format!("{stem}.svg")),
                report.figure_svg(fig, FigureSize::default())?,
            )?;
            std::fs::write(
                dir.join(format!("{stem}.png")),
                report.figure_png(fig, FigureSize::default())?,
            )?;
            std::fs::write(
                dir.join(format!("{stem}_small.png")),
                report.figure_png(
                    fig,
                    FigureSize {
                        width: 480,
                        height: 320,
                    },
                )?,
            )?;
        }
    }
    println!("written to {}", dir.display());
    Ok(())
}
