//! Every `surfcap-bench ...` command example of `README.md` and of the user guide (every `.md`
//! under `docs/`) parses against the benchmark program's command line, so the documented
//! benchmark commands cannot drift from `surfcap-bench --help`.

use surfcap_bench::Cli;
use surfcap_testkit::doc_examples::assert_doc_examples_parse;
use surfcap_testkit::workspace_root;

#[test]
fn every_surfcap_bench_example_in_the_docs_parses() {
    assert_doc_examples_parse::<Cli>(&workspace_root(), "surfcap-bench");
}
