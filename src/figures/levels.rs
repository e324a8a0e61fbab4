//! The figures of `hyst levels --svg-dir`.

/// Each level's k∞ and Ω (± one standard error) against its σₓ, beside the model's own
/// statistical linearization there.
pub fn levels_figures(
    dir: &std::path::Path,
    r: &crate::ident::levels::LevelsReport,
) -> Result<(), String> {
    use crate::plot::{chart, colors};
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let at = |v: &dyn Fn(usize) -> Option<f64>| -> Vec<(f64, f64)> {
        (0..r.levels.len())
            .filter_map(|i| v(i).map(|y| (r.levels[i].sigma_x, y)))
            .collect()
    };
    for (j, file, title, yl) in [
        (
            2,
            "levels_kinf.svg",
            "Zener stiffness k∞ by level",
            "k∞ (N/m)",
        ),
        (
            3,
            "levels_omega.svg",
            "Corner frequency Ω by level",
            "Ω (rad/s)",
        ),
    ] {
        let fit = |i: usize| &r.levels[i].fit;
        let value = |i: usize| if j == 2 { fit(i).k_inf } else { fit(i).omega };
        let model = |i: usize| {
            r.levels[i]
                .model_zener
                .map(|z| if j == 2 { z.k_inf } else { z.omega })
        };
        chart(
            &dir.join(file),
            title,
            "σₓ of the record (m)",
            yl,
            &[
                ("identified".into(), at(&|i| Some(value(i))), colors::BLUE),
                (
                    "− SE".into(),
                    at(&|i| Some(value(i) - fit(i).se[j])),
                    colors::GREY,
                ),
                (
                    "+ SE".into(),
                    at(&|i| Some(value(i) + fit(i).se[j])),
                    colors::GREY,
                ),
                (
                    "the model's statistical linearization".into(),
                    at(&model),
                    colors::BLACK,
                ),
            ],
        )?;
    }
    Ok(())
}
