//! Every `surfcap ...` command example of `README.md` and of the user guide (every `.md` under
//! `docs/`: the book's chapters, the formats, results and development pages it includes) parses
//! against the program's command line, so the documentation cannot drift
//! from `--help`. Examples are found by `surfcap_testkit::doc_examples` (```` ```sh ````,
//! ```` ```bash ```` and ```` ```console ```` blocks); shell variables such as `$WORK` stay words,
//! which clap takes as the file names they stand for.

use clap::Parser;
use surfcap_cli::Cli;
use surfcap_testkit::{doc_examples, workspace_root};

#[test]
fn every_surfcap_example_in_the_docs_parses() {
    let root = workspace_root();
    let examples = doc_examples(&root, "surfcap").expect("the docs are readable");
    assert!(
        !examples.is_empty(),
        "no `surfcap ...` example found in {}/README.md or docs/**/*.md (```sh blocks)",
        root.display()
    );
    let failures: Vec<String> = examples
        .iter()
        .filter_map(|ex| match Cli::try_parse_from(&ex.words) {
            Ok(_) => None,
            // `--help` and `--version` examples are fine: clap reports them as "errors".
            Err(e)
                if matches!(e.kind(), clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion) =>
            {
                None
            }
            Err(e) => Some(format!("{}:{}: {}\n{}", ex.file.display(), ex.line, ex.words.join(" "), e.render())),
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} command examples do not parse:\n\n{}",
        failures.len(),
        examples.len(),
        failures.join("\n")
    );
}
