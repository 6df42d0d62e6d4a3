//! The parameter table of `docs/parameters.md` and `config/cstep.yaml` are written from the one
//! definition of every parameter, `cstep::parameters::PARAMETERS`: these tests render both and
//! fail when a file differs. After changing the table, rewrite them with
//! `CSTEP_WRITE_DOCS=1 cargo test --test parameter_docs` (or `make parameter-docs`).

use std::path::{Path, PathBuf};

use cstep::parameters::{load_all, BUILTIN_URDF, DEFAULT_NODE_NAME};
use cstep::parameters::{Change, Parameter, Value, BUILTIN_URDF_PATH, PARAMETERS};

/// How to rewrite the files, said in every failure.
const REWRITE: &str = "CSTEP_WRITE_DOCS=1 cargo test --test parameter_docs";

/// The page that holds the generated parameter table, between its markers.
const TABLE_PAGE: &str = "docs/parameters.md";

/// Where the page's table starts and ends.
const TABLE_START: &str =
    "<!-- parameters: written from cstep-core's parameter table by `make parameter-docs` -->\n";
const TABLE_END: &str = "<!-- parameters: end -->\n";

/// `robot_description` in the shipped file: the URDF beside it, which is the compiled-in one.
const SHIPPED_URDF: &str = "../urdf/cf2x.urdf";

/// Width of the YAML file's comment lines.
const WIDTH: usize = 100;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// "read-only" or "live".
fn change(p: &Parameter) -> &'static str {
    match p.change {
        Change::Live => "live",
        Change::ReadOnly => "read-only",
    }
}

/// The line under a parameter's description: type, unit, accepted values, liveness.
fn summary(p: &Parameter) -> String {
    let unit = p.unit.map_or_else(String::new, |u| format!(", {u}"));
    format!(
        "{}{unit}, {}; {}",
        p.rule.kind().name(),
        p.rule.constraint(),
        change(p)
    )
}

/// `text` as comment lines of at most [`WIDTH`] characters, each starting with `indent# `.
fn comment(text: &str, indent: &str) -> String {
    let mut out = String::new();
    let mut line = format!("{indent}#");
    for word in text.split_whitespace() {
        if line.chars().count() + 1 + word.chars().count() > WIDTH && line.ends_with(|c| c != '#') {
            out.push_str(&line);
            out.push('\n');
            line = format!("{indent}#");
        }
        line.push(' ');
        line.push_str(word);
    }
    out.push_str(&line);
    out.push('\n');
    out
}

/// `config/cstep.yaml` as the table defines it.
fn yaml_file() -> String {
    let mut out = String::from(
        "# cstep — default parameters, in ROS 2 `ros__parameters` form.\n\
         # Load with `cstep node --config config/cstep.yaml` (or `--ros-args --params-file ...`);\n\
         # override one with `-p name:=value`. Relative paths are relative to this file.\n\
         # Written from the table in crates/cstep-core/src/parameters/table.rs by\n\
         # `make parameter-docs`: change a parameter there, not here. Each one: what it means,\n\
         # then its type, unit, accepted values and whether it can change while the node runs\n\
         # (live) or not (read-only).\n\
         # `/**` applies to every node, whatever its name and namespace (rcl's wildcard, as\n\
         # launch_ros writes it), so the file serves `-r __ns:=/drone1` and launch files as is.\n\
         /**:\n  ros__parameters:\n",
    );
    for p in PARAMETERS {
        let value = if p.default == BUILTIN_URDF_PATH {
            SHIPPED_URDF
        } else {
            p.default
        };
        out.push_str(&comment(p.description, "    "));
        out.push_str(&comment(&summary(p), "    "));
        out.push_str(&format!("    {}: {value}\n", p.name));
    }
    out
}

/// The page's parameter table as the table defines it, between its markers.
fn parameter_table() -> String {
    // `|` would end the cell and `<properties>` would read as an HTML tag.
    let cell = |s: &str| s.replace('|', "\\|").replace('<', "&lt;");
    let mut out = String::from(TABLE_START);
    out.push_str("| parameter | type | default | accepted | unit | change | meaning |\n");
    out.push_str("|---|---|---|---|---|---|---|\n");
    for p in PARAMETERS {
        out.push_str(&format!(
            "| `{}` | {} | `{}` | {} | {} | {} | {} |\n",
            p.name,
            p.rule.kind().name(),
            p.default,
            cell(&p.rule.constraint()),
            p.unit.unwrap_or(""),
            change(p),
            cell(p.description),
        ));
    }
    out.push_str(TABLE_END);
    out
}

/// Whether this run rewrites the files instead of checking them.
fn writing() -> bool {
    std::env::var_os("CSTEP_WRITE_DOCS").is_some_and(|v| v == "1")
}

#[test]
fn config_yaml_is_written_from_the_table() {
    let path = repo("config/cstep.yaml");
    let expected = yaml_file();
    if writing() {
        std::fs::write(&path, &expected).unwrap();
    }
    let actual = std::fs::read_to_string(&path).unwrap();
    assert!(
        actual == expected,
        "config/cstep.yaml differs from the table in cstep-core's parameters/table.rs; rewrite it with \
         `{REWRITE}`. Expected:\n{expected}"
    );
}

#[test]
fn parameter_page_table_is_written_from_the_table() {
    let path = repo(TABLE_PAGE);
    let page = std::fs::read_to_string(&path).unwrap();
    let start = page
        .find(TABLE_START)
        .unwrap_or_else(|| panic!("{TABLE_PAGE} marks its parameter table with {TABLE_START}"));
    let end = page[start..]
        .find(TABLE_END)
        .expect("the table's end marker")
        + start;
    let current = &page[start..end + TABLE_END.len()];
    let expected = parameter_table();
    if writing() {
        std::fs::write(&path, page.replace(current, &expected)).unwrap();
    } else {
        assert!(
            current == expected,
            "{TABLE_PAGE}'s parameter table differs from the table in cstep-core's \
             parameters/table.rs; rewrite it with `{REWRITE}`. Expected:\n{expected}"
        );
    }
}

#[test]
fn the_shipped_file_sets_every_parameter_to_its_built_in_default() {
    let path = repo("config/cstep.yaml");
    let (_, _, shipped) = load_all(&[&path], DEFAULT_NODE_NAME, &[]).unwrap();
    let (_, _, builtin) = load_all(&[], DEFAULT_NODE_NAME, &[]).unwrap();
    for ((p, file), (_, default)) in shipped.iter().zip(builtin.iter()) {
        if p.name == "robot_description" {
            let Some(Value::Text(urdf)) = file else {
                panic!("{file:?}")
            };
            assert_eq!(std::fs::read_to_string(urdf).unwrap(), BUILTIN_URDF);
        } else {
            assert_eq!(file, default, "{}", p.name);
        }
    }
}
