//! What the campaign tests share.

use hyst_monitor::campaign::Campaign;

/// An unsigned setting from the environment, or `default`.
pub fn from_env(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .unwrap_or(default)
}

/// The campaigns a test runs: `HYST_CAMPAIGNS` (default 1) of `HYST_CAMPAIGN_DAYS` days
/// (default `days`) at 12 records a day, from `HYST_CAMPAIGN_SEED` (default `seed`), 100 000
/// seeds apart (record i of a campaign uses seed + i: nearby seeds would share their
/// records' noise, shifted).
pub fn campaigns(seed: u64, days: u64) -> impl Iterator<Item = Campaign> {
    let first = from_env("HYST_CAMPAIGN_SEED", seed);
    let days = from_env("HYST_CAMPAIGN_DAYS", days) as usize;
    (0..from_env("HYST_CAMPAIGNS", 1)).map(move |k| {
        let mut c = Campaign::default();
        c.days = days;
        c.per_day = 12;
        c.seed = first + 100_000 * k;
        c
    })
}

/// The analysis each record gets: `hyst ssi`'s, with 3 s of lags.
pub fn analysis() -> covssi::AnalysisOptions {
    covssi::AnalysisOptions::default().with_ssi(covssi::SsiOptions {
        block_rows: covssi::BlockRows::Seconds(3.0),
        ..covssi::SsiOptions::default()
    })
}
