//! Every `surfcap ...` command example of `README.md` and of the user guide (every `.md` under
//! `docs/`: the book's chapters, the formats, results and development pages it includes) parses
//! against the program's command line, so the documentation cannot drift
//! from `--help`. Examples are found by `surfcap_testkit::doc_examples` (```` ```sh ````,
//! ```` ```bash ```` and ```` ```console ```` blocks); shell variables such as `$WORK` stay words,
//! which clap takes as the file names they stand for.

use surfcap_cli::Cli;
use surfcap_testkit::doc_examples::assert_doc_examples_parse;
use surfcap_testkit::workspace_root;

#[test]
fn every_surfcap_example_in_the_docs_parses() {
    assert_doc_examples_parse::<Cli>(&workspace_root(), "surfcap");
}
