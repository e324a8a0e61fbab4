//! One set of options in the command line and in Python: every flag of a command is a
//! keyword of its Python twin (the same name in snake case, `--no-x` as `x`), or is listed
//! below as one side's with the reason; every keyword likewise. The SSI settings both
//! `ssi` and `track` take are [`SsiSettings`]'s fields on both sides. A flag or keyword
//! added to one side alone fails these tests.

use clap::CommandFactory;
use hyst::settings::{SsiSettings, TrackSettings};

use super::Cli;

/// A command and its Python function, with what only one side has and why.
struct Pair {
    command: &'static str,
    function: &'static str,
    /// (flag, keyword) that name one option differently.
    renamed: &'static [(&'static str, &'static str)],
    /// Flags without a keyword, each with its reason.
    cli_only: &'static [(&'static str, &'static str)],
    /// Keywords without a flag, each with its reason.
    python_only: &'static [(&'static str, &'static str)],
}

/// Flags every command has that are not options of the analysis.
const EVERY_COMMAND: &[(&str, &str)] = &[
    ("help", "the command line's help"),
    ("format", "how files are read: hyst.read(path, format=)"),
    (
        "delimiter",
        "how files are read: hyst.read(path, delimiter=)",
    ),
    ("variable", "how files are read: hyst.read(path, variable=)"),
    (
        "names",
        "how files are read: hyst.read(path).names is a list Python sets",
    ),
];

const FILES: &str = "Python returns the result: report.to_dict(), str(report)";

const PAIRS: &[Pair] = &[
    Pair {
        command: "amplitude",
        function: "amplitude",
        renamed: &[],
        cli_only: &[
            ("input", "Python takes the array y"),
            (
                "columns",
                "Python selects the array's columns: y[:, [0, 2]]",
            ),
            ("skip", "Python slices the array: y[skip:]"),
            ("gains", "Python divides the array's columns: y / gains"),
            ("json", FILES),
            ("svg", FILES),
            (
                "model",
                "not yet in Python: the fitted model's records beside the measured ones are the command's (noted in issue 60's close)",
            ),
        ],
        python_only: &[
            ("y", "the array; the command reads --input"),
            (
                "record",
                "a name for the report; the command's is the file's path",
            ),
        ],
    },
    Pair {
        command: "ssi",
        function: "ssi",
        renamed: &[("input", "y")],
        cli_only: &[
            (
                "columns",
                "Python selects the array's columns: y[:, [0, 2]]",
            ),
            ("skip", "Python slices the array: y[skip:]"),
            ("gains", "Python divides the array's columns: y / gains"),
            ("json", "Python: result.to_json()"),
            (
                "svg",
                "Python draws result.poles and result.pole_status (matplotlib), or result.html()",
            ),
            ("shapes-uff", "Python: result.write_shapes_uff(path)"),
            ("html", "Python: result.html() (report.html() for setups)"),
            (
                "json-diagrams",
                "the command's --json file only: Python's report of setups keeps every setup's diagram in report.to_dict()",
            ),
        ],
        python_only: &[
            (
                "channels",
                "the array's channel names; the command reads them from the file",
            ),
            (
                "record",
                "a name for the report; the command's is the file's path",
            ),
            (
                "fdd",
                "the page's FDD; the command computes it when --html asks for the page",
            ),
        ],
    },
    Pair {
        command: "track",
        function: "track",
        renamed: &[("inputs", "records")],
        cli_only: &[
            (
                "input",
                "one long file cut into windows: Python cuts the array",
            ),
            (
                "window",
                "one long file cut into windows: Python cuts the array",
            ),
            (
                "step",
                "one long file cut into windows: Python cuts the array",
            ),
            ("columns", "Python selects the arrays' columns"),
            (
                "estimates",
                "another system's estimates: Python's hyst.track_estimates",
            ),
            (
                "out",
                "the command's store and tables; Python returns the report",
            ),
            ("svg-dir", FILES),
            ("html", "Python: report.html()"),
            (
                "follow",
                "Python: hyst.follow(folders, ...), an iterator of the lines the command prints",
            ),
            ("poll", "Python: hyst.follow(poll=)"),
        ],
        python_only: &[
            (
                "times",
                "each array's time; the command reads it from --covariates' `time` column",
            ),
            (
                "client",
                "a Dask cluster identifies the records; the command runs on one machine",
            ),
        ],
    },
    Pair {
        command: "ident",
        function: "identify",
        renamed: &[("data", "y")],
        cli_only: &[
            ("output-column", "Python takes the output array"),
            (
                "input-column",
                "the input column is used by --validate files only",
            ),
            ("skip", "Python slices the array"),
            (
                "validation-kind",
                "Python gives each validation record's `periodic`",
            ),
            ("json", FILES),
            ("svg-dir", FILES),
        ],
        python_only: &[(
            "record",
            "a name for the report; the command's is the file's path",
        )],
    },
    Pair {
        command: "refine",
        function: "refine",
        renamed: &[],
        cli_only: &[
            (
                "data",
                "the file of input and output; Python takes the arrays u and y",
            ),
            ("input-column", "Python takes the input array u"),
            ("output-column", "Python takes the output array y"),
            ("json", FILES),
            ("svg-dir", FILES),
        ],
        python_only: &[
            ("u", "the input array; the command reads --data"),
            ("y", "the output array; the command reads --data"),
            (
                "record",
                "a name for the report; the command's is the file's path",
            ),
        ],
    },
    Pair {
        command: "levels",
        function: "levels",
        renamed: &[("data", "records")],
        cli_only: &[
            ("output-column", "Python takes the output arrays"),
            (
                "input-column",
                "the input column is used by --validate files only",
            ),
            ("skip", "Python slices the arrays"),
            (
                "periodic",
                "Python gives each validation record's `periodic`",
            ),
            ("json", FILES),
            ("svg-dir", FILES),
            (
                "channels",
                "Python takes each record as an array (samples, channels)",
            ),
        ],
        python_only: &[],
    },
    Pair {
        command: "simulate",
        function: "simulate",
        renamed: &[("input", "u")],
        cli_only: &[
            ("column", "Python takes the force array"),
            ("system", "Python: model=\"benchmark\""),
            ("params", "Python: model as a dict of the same schema"),
            ("excitation", "Python: u = hyst.excite(excitation=...)"),
            ("rms", "Python: u = hyst.excite(rms=...)"),
            ("samples", "Python: u = hyst.excite(samples=...)"),
            ("seed", "Python: u = hyst.excite(seed=...)"),
            ("f-min", "Python: u = hyst.excite(f_min=...)"),
            ("f-max", "Python: u = hyst.excite(f_max=...)"),
            ("out", "Python returns the response"),
            (
                "structure",
                "Python: model = a storey fit's dict, hyst.levels(..., masses=...).to_dict()",
            ),
            (
                "forces",
                "Python takes the forces as u, one column per loaded floor",
            ),
            (
                "measured",
                "Python compares the returned array with its own: numpy does it in a line",
            ),
            ("channels", "Python selects the measured array's columns"),
            ("compare-skip", "Python slices the arrays"),
        ],
        python_only: &[(
            "model",
            "the model; the command's --system, --params or --structure",
        )],
    },
    Pair {
        command: "excite",
        function: "excite",
        renamed: &[],
        cli_only: &[("out", "Python returns the force")],
        python_only: &[],
    },
];

/// A command's long flags, without the leading dashes.
fn flags(command: &str) -> Vec<String> {
    let cli = Cli::command();
    let sub = cli
        .find_subcommand(command)
        .unwrap_or_else(|| panic!("no command {command}"));
    sub.get_arguments()
        .filter_map(|a| a.get_long().map(str::to_string))
        .collect()
}

/// The parameters of `def name(` in Python source `src`, in order (annotations and
/// defaults dropped; `*` and `self` are not parameters).
fn python_parameters(src: &str, name: &str) -> Vec<String> {
    let start = src
        .find(&format!("\ndef {name}("))
        .unwrap_or_else(|| panic!("no def {name}"))
        + name.len()
        + 6;
    let mut depth = 0usize;
    let mut current = String::new();
    let mut items = Vec::new();
    for c in src[start..].chars() {
        match c {
            '(' | '[' | '{' => depth += 1,
            ']' | '}' => depth -= 1,
            ')' if depth == 0 => break,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                items.push(std::mem::take(&mut current));
                continue;
            }
            _ => {}
        }
        current.push(c);
    }
    items.push(current);
    items
        .iter()
        .map(|i| {
            i.split([':', '='])
                .next()
                .unwrap_or_default()
                .trim()
                .to_string()
        })
        .filter(|n| !n.is_empty() && n != "*" && n != "self")
        .collect()
}

fn python_source(file: &str) -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/crates/hyst-py/python/hyst/");
    std::fs::read_to_string(format!("{path}{file}")).expect("the Python package's source")
}

/// Every module of the Python package (`__init__.py` and the modules it imports its
/// functions from), one after another, in name order.
fn python_package() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/crates/hyst-py/python/hyst");
    let mut files: Vec<_> = std::fs::read_dir(path)
        .expect("the Python package's folder")
        .map(|e| e.expect("an entry of the package's folder").path())
        .filter(|p| p.extension().is_some_and(|e| e == "py"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|p| std::fs::read_to_string(p).expect("a module of the Python package"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The keyword a flag is on the Python side, by the naming rule: snake case, `no-x` as `x`.
fn keyword_of(flag: &str) -> String {
    flag.strip_prefix("no-").unwrap_or(flag).replace('-', "_")
}

#[test]
fn every_flag_has_its_keyword_and_every_keyword_its_flag() {
    let src = python_package();
    let mut problems = Vec::new();
    for p in PAIRS {
        let keywords = python_parameters(&src, p.function);
        let command_flags = flags(p.command);
        let listed = |list: &[(&str, &str)], name: &str| list.iter().any(|(n, _)| *n == name);
        for flag in &command_flags {
            let flag = flag.as_str();
            if listed(EVERY_COMMAND, flag) || listed(p.cli_only, flag) {
                continue;
            }
            let keyword = p
                .renamed
                .iter()
                .find(|(f, _)| *f == flag)
                .map_or_else(|| keyword_of(flag), |(_, k)| k.to_string());
            if !keywords.contains(&keyword) {
                problems.push(format!(
                    "hyst {} --{flag} has no keyword `{keyword}` in hyst.{}",
                    p.command, p.function
                ));
            }
        }
        let cli: Vec<String> = command_flags
            .iter()
            .map(|f| {
                p.renamed
                    .iter()
                    .find(|(cf, _)| cf == f)
                    .map_or_else(|| keyword_of(f), |(_, k)| k.to_string())
            })
            .collect();
        for k in &keywords {
            if k != "fs" && !cli.contains(k) && !listed(p.python_only, k) {
                problems.push(format!(
                    "hyst.{}({k}=) has no flag in hyst {}",
                    p.function, p.command
                ));
            }
        }
        // What is listed as one side's must not be on the other side too.
        for (flag, _) in p.cli_only {
            if keywords.contains(&keyword_of(flag)) {
                problems.push(format!(
                    "--{flag} is listed as the command's alone, but hyst.{} has it",
                    p.function
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn ssi_and_track_take_every_ssi_setting_on_both_sides() {
    let src = python_package();
    let stub = python_source("__init__.pyi");
    for (command, function) in [("ssi", "ssi"), ("track", "track")] {
        let cli: Vec<String> = flags(command).iter().map(|f| keyword_of(f)).collect();
        let py = python_parameters(&src, function);
        let typed = python_parameters(&stub, function);
        for name in SsiSettings::names() {
            assert!(
                cli.contains(&name),
                "hyst {command} lacks the setting {name}"
            );
            assert!(
                py.contains(&name),
                "hyst.{function} lacks the setting {name}"
            );
            assert!(
                typed.contains(&name),
                "__init__.pyi's {function} lacks the setting {name}"
            );
        }
    }
}

#[test]
fn track_takes_every_tracking_setting_on_both_sides() {
    let src = python_package();
    let stub = python_source("__init__.pyi");
    let cli: Vec<String> = flags("track").iter().map(|f| keyword_of(f)).collect();
    let py = python_parameters(&src, "track");
    let typed = python_parameters(&stub, "track");
    for name in TrackSettings::names() {
        assert!(cli.contains(&name), "hyst track lacks the setting {name}");
        assert!(py.contains(&name), "hyst.track lacks the setting {name}");
        assert!(
            typed.contains(&name),
            "__init__.pyi's track lacks the setting {name}"
        );
    }
}

#[test]
fn the_type_stubs_list_the_same_keywords_as_the_package() {
    let src = python_package();
    let stub = python_source("__init__.pyi");
    for p in PAIRS {
        let mut a = python_parameters(&src, p.function);
        let mut b = python_parameters(&stub, p.function);
        a.sort();
        b.sort();
        assert_eq!(a, b, "hyst.{} in the package and __init__.pyi", p.function);
    }
}

#[test]
fn python_parameters_reads_annotations_and_defaults() {
    let src = "x\ndef f(a, b: Optional[tuple[int, int]] = ..., *, c=(1, 2), d={\"k\": 1}):\n";
    assert_eq!(python_parameters(src, "f"), ["a", "b", "c", "d"]);
}
