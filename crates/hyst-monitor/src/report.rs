//! The text of a [`TrackReport`]: what `hyst track` prints.

use std::fmt;

use crate::chart::Side;
use crate::track::TrackReport;

impl TrackReport {
    /// Mode `j`'s line: its reference, tracking share, baseline, environmental model,
    /// extrapolated records and slow effect.
    fn fmt_mode(
        &self,
        f: &mut fmt::Formatter<'_>,
        j: usize,
        m: &crate::ModeEstimate,
    ) -> fmt::Result {
        write!(
            f,
            "mode {}: {:.4} Hz, damping ratio {:.4} ({:.2} %), tracked in {:.1} % of the records",
            self.mode_name(j),
            m.frequency_hz,
            m.damping_ratio,
            100.0 * m.damping_ratio,
            100.0 * self.tracked.get(j).copied().unwrap_or(0.0)
        )?;
        match (self.baselines.get(j), self.baseline_errors.get(j)) {
            (Some(Some(b)), _) => {
                let names = self.regressor_names(j, b.coefficients.len() - 1);
                let slopes: Vec<String> = b.coefficients[1..]
                    .iter()
                    .zip(&names)
                    .map(|(v, name)| format!("{v:+.3e} Hz per unit of {name}"))
                    .collect();
                writeln!(
                    f,
                    "; baseline {:.4} Hz at zero covariates{}; SD {:.2e} Hz unexplained beyond the estimation noise ({} training records)",
                    b.coefficients[0],
                    if slopes.is_empty() {
                        String::new()
                    } else {
                        format!(", {}", slopes.join(", "))
                    },
                    b.unexplained_sd_hz,
                    b.records
                )?;
                if let Some(Some(s)) = self.noise_from_training.get(j) {
                    writeln!(
                        f,
                        "  no standard errors given: the estimation noise read from the training rows' consecutive differences, {s:.3e} Hz"
                    )?;
                }
                if let Some(Some(e)) = self.environments.get(j)
                    && e.bic_gain < 0.0
                {
                    writeln!(
                        f,
                        "  environmental model chosen on the training records (BIC {:+.1} against the covariates as they are, linear)",
                        e.bic_gain
                    )?;
                }
                let outside = self
                    .rows
                    .iter()
                    .filter(|r| r.mode == j && r.extrapolated)
                    .count();
                if outside > 0 {
                    writeln!(
                        f,
                        "  {outside} record(s) with covariates outside the training range: their predictions extrapolated (column `extrapolated`)"
                    )?;
                }
                if let Some(Some(m)) = self.residual_models.get(j) {
                    writeln!(
                        f,
                        "  a slow effect the covariates do not explain: SD {:.2e} Hz, correlation {:.3} from record to record; its filter's innovations charted, which keep {:.0} % of a lasting change once settled (a covariate that explains the effect keeps it all)",
                        m.latent_var.sqrt(),
                        m.persistence,
                        100.0 * m.lasting_change_share
                    )?;
                }
            }
            (_, Some(Some(e))) => writeln!(f, "; no baseline: {e}")?,
            _ => writeln!(f)?,
        }
        if let Some(Some(c)) = self.calibrations.get(j) {
            fmt_calibration(f, c)?;
        }
        Ok(())
    }

    /// The joint chart's lines, or why it was not drawn.
    fn fmt_joint(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(c) = &self.joint {
            let names: Vec<String> = c.modes.iter().map(|&j| self.mode_name(j)).collect();
            let eigen: Vec<String> = c.eigenvalues.iter().map(|l| format!("{l:.2}")).collect();
            writeln!(
                f,
                "modes judged together ({}; trained on {} records holding them all): {} factor(s) they share (eigenvalues of their residuals' correlations {} against {:.2} for independent residuals); the statistic of what the shared factors leave charted, limit h = {:.2}",
                names.join(", "),
                c.trained_on,
                c.common_factors,
                eigen.join(", "),
                c.noise_edge,
                c.limit
            )?;
            if let Some(cal) = &c.calibration {
                fmt_calibration(f, cal)?;
            }
            if c.alarms.is_empty() {
                writeln!(f, "  the joint chart raised no alarm")?;
            }
            // The first few: a lasting change raises one every few records after.
            const SAID: usize = 5;
            for a in c.alarms.iter().take(SAID) {
                writeln!(f, "{}", self.joint_alarm_line(a))?;
            }
            if c.alarms.len() > SAID {
                let last = &c.alarms[c.alarms.len() - 1];
                writeln!(
                    f,
                    "  and {} more alarm(s) of the modes judged together, the last at record {} (all in report.json's `joint.alarms`)",
                    c.alarms.len() - SAID,
                    self.record_name(last.record)
                )?;
            }
        }
        if let Some(e) = &self.joint_error {
            writeln!(f, "modes not judged together: {e}")?;
        }
        Ok(())
    }

    /// The harmonics named, one line for all: each line's frequency and its records.
    fn fmt_harmonics(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !self.harmonics.is_empty() {
            let mut lines: Vec<(f64, usize)> = Vec::new();
            for &(_, hz) in &self.harmonics {
                // One line per harmonic: its estimates within 0.5 % of each other.
                match lines.iter_mut().find(|(g, _)| (hz - *g).abs() <= 0.005 * g) {
                    Some(l) => l.1 += 1,
                    None => lines.push((hz, 1)),
                }
            }
            lines.sort_by(|a, b| a.0.total_cmp(&b.0));
            let said: Vec<String> = lines
                .iter()
                .map(|(hz, n)| format!("{hz:.4} Hz in {n} record(s)"))
                .collect();
            writeln!(
                f,
                "harmonics (steady spectral lines: a machine's, not the structure's; not tracked): {}",
                said.join(", ")
            )?;
        }
        Ok(())
    }

    /// The subspace test's line, or why it was not run.
    fn fmt_subspace(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(c) = &self.subspace {
            let after = c.t2.len().saturating_sub(c.training);
            writeln!(
                f,
                "subspace damage test (no mode picking; a residual of {} entries, trained on {} records): {} of {} later records above its threshold T² {:.1} at {} % per record (normal theory's {:.1}); its CUSUM {}",
                c.dof,
                c.trained_on,
                c.above_threshold.len(),
                after,
                c.threshold,
                100.0 * c.alpha,
                c.nominal_threshold,
                if c.alarms.is_empty() {
                    "raised no alarm".to_string()
                } else if c.directions > 0 {
                    format!(
                        "alarmed {} time(s), the first at record {} (below)",
                        c.mode_alarms.len(),
                        self.record_name(c.alarms[0])
                    )
                } else {
                    format!("alarmed at record(s) {:?}", c.alarms)
                }
            )?;
            if c.directions > 0 {
                let names = self.subspace_mode_names(c.directions);
                writeln!(
                    f,
                    "  charted: each of the {} reference modes' frequency change estimated from the residual (along its sensitivity; the full T² spreads it over all {} entries), two-sided, limits h = {}",
                    c.directions,
                    c.dof,
                    c.mode_limits
                        .iter()
                        .map(|h| format!("{h:.2}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )?;
                for a in c.mode_alarms.iter().take(5) {
                    writeln!(f, "  {}", self.subspace_alarm_line(c, a, &names))?;
                }
                if c.mode_alarms.len() > 5 {
                    writeln!(
                        f,
                        "    and {} more alarm(s) of the subspace test (all in report.json's `subspace.mode_alarms`)",
                        c.mode_alarms.len() - 5
                    )?;
                }
            }
            if let Some(m) = &c.scale_model {
                writeln!(
                    f,
                    "  each record's residual covariance scaled by its own estimation noise (from its {} parts): c = {:.3} + {:.4e} × its scatter per entry (c from {:.2} to {:.2} over the records)",
                    crate::subspace::PARTS,
                    m.intercept,
                    m.slope,
                    c.scale
                        .iter()
                        .copied()
                        .filter(|v| v.is_finite())
                        .fold(f64::INFINITY, f64::min),
                    c.scale
                        .iter()
                        .copied()
                        .filter(|v| v.is_finite())
                        .fold(f64::NEG_INFINITY, f64::max),
                )?;
            }
        }
        if let Some(e) = &self.subspace_error {
            writeln!(f, "subspace damage test not run: {e}")?;
        }
        Ok(())
    }

    /// The line of an alarm of the subspace test's chart of one mode (`names`: the
    /// directions' names).
    fn subspace_alarm_line(
        &self,
        c: &crate::subspace::SubspaceChart,
        a: &crate::subspace::SubspaceAlarm,
        names: &[String],
    ) -> String {
        format!(
            "ALARM (subspace test): mode {} {} at record {} (time {} s), its frequency estimated {:+.2} % from the reference's prediction",
            names.get(a.mode).map_or("?", String::as_str),
            if a.side == crate::Side::Up {
                "rose"
            } else {
                "fell"
            },
            self.record_name(a.record),
            c.time.get(a.record).copied().unwrap_or(f64::NAN),
            100.0 * a.shift
        )
    }

    /// The subspace test's `count` directions named as the reference's modes when they are
    /// as many (both in ascending frequency), else "pole k" from 1.
    fn subspace_mode_names(&self, count: usize) -> Vec<String> {
        if self.reference.len() == count {
            let mut by_frequency: Vec<usize> = (0..count).collect();
            by_frequency.sort_by(|&a, &b| {
                self.reference[a]
                    .frequency_hz
                    .total_cmp(&self.reference[b].frequency_hz)
            });
            by_frequency
                .iter()
                .map(|&j| {
                    self.mode_names
                        .get(j)
                        .cloned()
                        .unwrap_or_else(|| format!("{}", j + 1))
                })
                .collect()
        } else {
            (1..=count).map(|k| format!("(pole {k})")).collect()
        }
    }

    /// The names of mode `j`'s `count` regressors: each covariate, lagged, and its hinge or
    /// curvature.
    fn regressor_names(&self, j: usize, count: usize) -> Vec<String> {
        let name = |c: usize| {
            self.covariate_names
                .get(c)
                .cloned()
                .unwrap_or_else(|| format!("covariate {c}"))
        };
        let mut names = Vec::with_capacity(count);
        match self.environments.get(j) {
            Some(Some(e)) => {
                for t in &e.terms {
                    let lagged = if t.lag_s > 0.0 {
                        format!("{} ({:.3} h earlier)", name(t.covariate), t.lag_s / 3600.0)
                    } else {
                        name(t.covariate)
                    };
                    names.push(lagged.clone());
                    if let Some(c) = t.breakpoint {
                        names.push(format!("{lagged} below {c:.4}"));
                    }
                    if let Some(m) = t.quadratic_about {
                        names.push(format!("({lagged} − {m:.4})²"));
                    }
                }
            }
            _ => names.extend((0..count).map(name)),
        }
        names.resize_with(count, || "?".into());
        names
    }
}

/// A chart limit's calibration, one indented line.
fn fmt_calibration(f: &mut fmt::Formatter<'_>, c: &crate::calibration::Calibration) -> fmt::Result {
    let how = if c.bootstrap_h > c.nominal_h {
        format!(
            "calibrated on its {} training values (lag-one correlation {:.2}; a block bootstrap in blocks of {})",
            c.values, c.lag_one, c.block
        )
    } else {
        format!(
            "the nominal limit, which the {} training values' block bootstrap does not ask to raise (it would go to {:.2}; no lower: a bootstrap cannot see a tail its values do not show)",
            c.values, c.bootstrap_h
        )
    };
    writeln!(
        f,
        "  chart limit h = {:.2}, {how}: one false alarm per {:.2e} records measured on them (the nominal h = {:.2} would give one per {:.2e})",
        c.h, c.run_length, c.nominal_h, c.nominal_run_length
    )
}

impl TrackReport {
    /// Every alarm as one line of text, in the order of the records that raised them: the
    /// modes' own (`ALARM: mode 2 fell at record …`), the modes judged together's (with the
    /// modes that drove it) and the subspace test's. A record's alarm reads the same in every
    /// report that holds it (what `hyst track --follow` prints as it comes).
    pub fn alarm_lines(&self) -> Vec<String> {
        let mut lines: Vec<(usize, String)> = Vec::new();
        for a in &self.alarms {
            lines.push((a.record, self.mode_alarm_line(a)));
        }
        if let Some(c) = &self.joint {
            for a in &c.alarms {
                lines.push((a.record, self.joint_alarm_line(a)));
            }
        }
        if let Some(c) = self.subspace.as_ref().filter(|c| c.directions > 0) {
            let names = self.subspace_mode_names(c.directions);
            for a in &c.mode_alarms {
                lines.push((a.record, self.subspace_alarm_line(c, a, &names)));
            }
        } else if let Some(c) = &self.subspace {
            for &i in &c.alarms {
                lines.push((
                    i,
                    format!(
                        "ALARM (subspace test) at record {} (time {} s)",
                        self.record_name(i),
                        c.time.get(i).copied().unwrap_or(f64::NAN)
                    ),
                ));
            }
        }
        lines.sort_by_key(|l| l.0);
        lines.into_iter().map(|l| l.1).collect()
    }

    /// The joint chart's alarm as its line of text, with the modes that drove it (those
    /// with a tenth of it or more).
    fn joint_alarm_line(&self, a: &crate::joint::JointAlarm) -> String {
        let drivers: Vec<String> = a
            .drivers
            .iter()
            .filter(|d| d.1 >= 0.1)
            .map(|&(j, share)| format!("mode {} ({:.0} %)", self.mode_name(j), 100.0 * share))
            .collect();
        format!(
            "ALARM (modes judged together) at record {} (time {} s), driven by {}",
            self.record_name(a.record),
            a.time,
            drivers.join(", ")
        )
    }

    /// A mode's alarm as its line of text.
    fn mode_alarm_line(&self, a: &crate::ModeAlarm) -> String {
        let way = match a.side {
            Side::Up => "rose",
            Side::Down => "fell",
        };
        format!(
            "ALARM: mode {} {way} at record {} (time {} s)",
            self.mode_name(a.mode),
            self.record_name(a.record),
            a.time
        )
    }

    /// Record `record`'s name, as its rows give it.
    fn record_name(&self, record: usize) -> &str {
        self.rows
            .iter()
            .find(|r| r.record == record)
            .map_or("?", |r| r.name.as_str())
    }
}

impl fmt::Display for TrackReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let records: std::collections::BTreeSet<usize> =
            self.rows.iter().map(|r| r.record).collect();
        writeln!(
            f,
            "{} reference mode(s); {} record(s) with modes, {} skipped",
            self.reference.len(),
            records.len(),
            self.skipped.len()
        )?;
        if !self.covariate_names.is_empty() {
            writeln!(
                f,
                "covariates: {}{}",
                self.covariate_names.join(", "),
                if self.level_covariate {
                    " (log_rms: ln of each record's RMS response, its excitation level)"
                } else {
                    ""
                }
            )?;
        }
        for (j, m) in self.reference.iter().enumerate() {
            self.fmt_mode(f, j, m)?;
        }
        for (name, why) in &self.skipped {
            writeln!(f, "skipped {name}: {why}")?;
        }
        for o in &self.training_outliers {
            let name = self.record_name(o.record);
            writeln!(
                f,
                "mode {}: training record {name} ({} Hz) set apart from the baseline: {}",
                self.mode_name(o.mode),
                o.frequency_hz,
                o.rule
            )?;
        }
        if !self.split.is_empty() {
            let mut per_mode = vec![0usize; self.reference.len()];
            for &(_, mode) in &self.split {
                if let Some(c) = per_mode.get_mut(mode) {
                    *c += 1;
                }
            }
            for (mode, count) in per_mode.iter().enumerate().filter(|(_, c)| **c > 0) {
                writeln!(
                    f,
                    "mode {} held twice, with one shape, in {count} record(s): which is the mode cannot be told, so it is not tracked there",
                    self.mode_name(mode)
                )?;
            }
        }
        self.fmt_harmonics(f)?;
        if !self.new_modes.is_empty() {
            writeln!(
                f,
                "{} mode(s) outside the reference, in {} record(s)",
                self.new_modes.len(),
                self.new_modes
                    .iter()
                    .map(|m| m.0)
                    .collect::<std::collections::BTreeSet<_>>()
                    .len()
            )?;
        }
        self.fmt_subspace(f)?;
        self.fmt_joint(f)?;
        if self.calibrations.iter().any(Option::is_some) {
            writeln!(
                f,
                "CUSUM of the standardized residuals (of their filter's innovations where a slow effect was found): each mode's limit calibrated on its training values for one false alarm per {:.3e} records (above)",
                self.in_control_run_length
            )?;
        } else {
            writeln!(
                f,
                "CUSUM of the standardized residuals (of their filter's innovations where a slow effect was found): one false alarm per {:.3e} records per mode when nothing changes and the values charted are independent",
                self.in_control_run_length
            )?;
        }
        if self.monitored == Some(0) {
            writeln!(
                f,
                "nothing monitored: every record trained the baselines (give fewer --training records than the campaign holds)"
            )?;
        } else if self.alarms.is_empty() && self.baselines.iter().all(Option::is_none) {
            writeln!(
                f,
                "nothing charted: no mode has a baseline (above), so the absence of an alarm says nothing"
            )?;
        } else if self.alarms.is_empty() {
            writeln!(f, "no alarm")?;
        }
        // Each mode's first few alarms: a lasting change raises one every few records after
        // its first, for as long as the campaign lasts.
        const SAID: usize = 5;
        let mut per_mode = vec![0usize; self.reference.len()];
        for a in &self.alarms {
            if let Some(n) = per_mode.get_mut(a.mode) {
                *n += 1;
                if *n <= SAID {
                    writeln!(f, "{}", self.mode_alarm_line(a))?;
                }
            }
        }
        for (mode, &n) in per_mode.iter().enumerate().filter(|(_, n)| **n > SAID) {
            let last = self.alarms.iter().rev().find(|a| a.mode == mode);
            writeln!(
                f,
                "  and {} more alarm(s) of mode {}, the last at record {} (all in report.json's `alarms`)",
                n - SAID,
                self.mode_name(mode),
                last.map_or("?", |a| self.record_name(a.record))
            )?;
        }
        Ok(())
    }
}
