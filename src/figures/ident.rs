//! The figures of `hyst ident --svg-dir`.

use crate::model::Oscillator;

/// Every figure of `hyst ident --svg-dir`: the stabilization diagram, figures like the
/// paper's 3(a) and 5, each model's hysteresis loop along the record, the Zener spectral
/// fit, and the implied input of each Bouc-Wen candidate when the excitation's band is known.
pub fn ident_figures(
    dir: &std::path::Path,
    r: &crate::ident::IdentReport,
    y: &[f64],
    fs: f64,
    validations: &[crate::ident::ValidationRecord],
) -> Result<(), String> {
    let id = &r.identification;
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let p = dir.join("stabilization.svg");
    let svg = crate::covssi::svg::stabilization_svg(
        &id.ssi.diagram,
        Some(4.0 * id.prepared.dominant_hz),
        "Stabilization diagram (output only)",
    );
    std::fs::write(&p, svg).map_err(|e| format!("{}: {e}", p.display()))?;
    paper_figures(dir, id, r.bouc_wen.as_ref(), validations)?;
    let p = &id.prepared;
    let mut models = vec![("linear", &r.linear)];
    models.extend(r.zener.as_ref().map(|z| ("Zener", z)));
    models.extend(r.bouc_wen.as_ref().map(|b| ("Bouc-Wen (kept)", b)));
    super::loops::loops_figure(
        &dir.join("hysteresis_loops.svg"),
        &models,
        &p.y,
        p.fs,
        p.dominant_hz,
        3.0,
    )?;
    if let Some(f) = &id.zener_spectrum {
        zener_spectrum_figure(&dir.join("zener_spectrum.svg"), y, fs, f)?;
    }
    if let Some(band) = r.options.excitation.filter(|_| id.flatness.is_some()) {
        let candidates: Vec<(String, Oscillator)> = r
            .candidates
            .iter()
            .map(|c| (c.route.name().to_string(), c.model))
            .collect();
        implied_input_figure(dir, &candidates, y, fs, &band)?;
    }
    Ok(())
}

/// Figures like the paper's 3(a) (the correlation function) and 5 (time and PSD overlays of
/// the identified models on the first validation record).
fn paper_figures(
    dir: &std::path::Path,
    id: &crate::ident::Identification,
    bouc_wen: Option<&Oscillator>,
    validations: &[crate::ident::ValidationRecord],
) -> Result<(), String> {
    use crate::plot::{chart, chart_log_y, colors};
    let p = &id.prepared;
    let lags = ((20.0 * p.fs / p.dominant_hz).ceil() as usize)
        .min(p.y.len() / 2)
        .max(2);
    let r = crate::covssi::corr::estimate(&[&p.y], &[0], lags);
    let corr: Vec<(f64, f64)> =
        r.r.iter()
            .enumerate()
            .map(|(k, v)| (k as f64 / p.fs, v[0]))
            .collect();
    chart(
        &dir.join("fig3a_correlation.svg"),
        "Fig. 3(a): unbiased autocorrelation of the output",
        "lag (s)",
        "R(τ) (m²)",
        &[("R̂xx".into(), corr, colors::BLACK)],
    )?;
    let Some(crate::ident::ValidationRecord {
        name,
        u,
        y,
        periodic,
        ..
    }) = validations.first()
    else {
        return Ok(());
    };
    let fs = p.fs * p.decimation as f64;
    let mut models: Vec<(&str, &crate::model::Oscillator, plotters::style::RGBColor)> =
        vec![("linear", &id.models.linear, colors::BLUE)];
    if let Some(z) = &id.models.zener {
        models.push(("Zener", z, colors::GREEN));
    }
    if let Some(b) = bouc_wen {
        models.push(("Bouc-Wen", b, colors::RED));
    }
    let n_time = ((0.5 * fs) as usize).min(y.len());
    let t = |v: &[f64]| -> Vec<(f64, f64)> {
        v.iter()
            .take(n_time)
            .enumerate()
            .map(|(k, x)| (k as f64 / fs, *x))
            .collect()
    };
    let psd = |v: &[f64]| -> Vec<(f64, f64)> {
        let (f, s) = crate::ident::welch_psd(v, fs, 512);
        f.into_iter().zip(s).collect()
    };
    let mut time = vec![("measured".to_string(), t(y), colors::BLACK)];
    let mut spec = vec![("measured".to_string(), psd(y), colors::BLACK)];
    for (label, m, c) in models {
        if let Ok(yhat) = crate::ident::simulate_model(m, u, fs, *periodic) {
            time.push((label.to_string(), t(&yhat), c));
            spec.push((label.to_string(), psd(&yhat), c));
        }
    }
    chart(
        &dir.join("fig5a_time.svg"),
        &format!("Fig. 5(a): response, {name}"),
        "t (s)",
        "x (m)",
        &time,
    )?;
    chart_log_y(
        &dir.join("fig5b_psd.svg"),
        &format!("Fig. 5(b): PSD, {name}"),
        "f (Hz)",
        "PSD (m²/Hz)",
        &spec,
    )?;
    Ok(())
}

/// The amplitude spectrum of the force each Bouc-Wen candidate implies, over the
/// excitation's band (dB re 1 N): the flatness fit is flat where the mapped models are not.
fn implied_input_figure(
    dir: &std::path::Path,
    candidates: &[(String, Oscillator)],
    y: &[f64],
    fs: f64,
    band: &crate::ident::flatness::ExcitationBand,
) -> Result<(), String> {
    use crate::plot::{chart, colors};
    let palette = [colors::RED, colors::BLUE, colors::GREEN, colors::BLACK];
    // Drawn in reverse so that the first candidate (the flatness fit) lies on top.
    let series: Vec<_> = candidates
        .iter()
        .enumerate()
        .rev()
        .filter_map(|(i, (name, m))| {
            let col = &palette[i % palette.len()];
            let spec = crate::ident::flatness::implied_spectrum(m, y, fs, band).ok()?;
            let db = spec
                .iter()
                .map(|&(f, a)| (f, 20.0 * a.max(1e-300).log10()))
                .collect();
            Some((name.clone(), db, *col))
        })
        .collect();
    chart(
        &dir.join("implied_input_spectrum.svg"),
        "Implied input over the excitation band (output only)",
        "f (Hz)",
        "|Û| per line (dB re 1 N)",
        &series,
    )?;
    Ok(())
}

/// The record's PSD (Welch, 4096-sample segments) beside the Zener spectral fit's, over the
/// fitted band, with the fit's noise floor.
fn zener_spectrum_figure(
    path: &std::path::Path,
    y: &[f64],
    fs: f64,
    fit: &crate::ident::zener_spectrum::ZenerSpectralFit,
) -> Result<(), String> {
    use crate::plot::{chart_log_y, colors};
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let centred: Vec<f64> = y.iter().map(|v| v - mean).collect();
    let (f, s) = crate::ident::welch_psd(&centred, fs, 4096);
    let (f, s): (Vec<f64>, Vec<f64>) = f
        .into_iter()
        .zip(s)
        .skip(1)
        .take_while(|(f, _)| *f <= fit.max_frequency_hz)
        .unzip();
    let model = fit.psd(&f);
    let floor = 2.0 * fit.noise_std * fit.noise_std / fs;
    chart_log_y(
        path,
        &format!(
            "Zener spectral fit: c = {:.2} ± {:.2}, k = {:.0}, k∞ = {:.0}, Ω = {:.1}",
            fit.c, fit.se[0], fit.k, fit.k_inf, fit.omega
        ),
        "f (Hz)",
        "PSD (units²/Hz)",
        &[
            (
                "record (Welch)".into(),
                f.iter().copied().zip(s).collect(),
                colors::BLACK,
            ),
            (
                "fitted Zener + noise".into(),
                f.iter().copied().zip(model).collect(),
                colors::BLUE,
            ),
            (
                "fitted noise floor".into(),
                f.iter().map(|&f| (f, floor)).collect(),
                colors::GREY,
            ),
        ],
    )?;
    Ok(())
}
