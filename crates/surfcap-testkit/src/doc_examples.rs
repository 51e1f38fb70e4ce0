//! The command examples of `README.md` and of every Markdown file under `docs/` (the user guide in
//! `docs/src/`, and `docs/formats.md`, `docs/development.md` and `docs/results/`, which the guide
//! includes), as words, so a test can parse each one against the program's argument parser.
//!
//! An example is a line of a fenced ```` ```sh ````, ```` ```bash ```` or ```` ```console ````
//! block whose first word is the program's name (`surfcap`, `surfcap-bench`). In a `console`
//! block only lines starting with the prompt `$ ` are commands (the others are output). A line
//! ending in an unquoted `\` continues on the next. Words are split as a POSIX shell splits
//! them for quoting: single quotes keep everything, double quotes keep everything but `\"`,
//! `\\`, `\$` and `` \` ``, a backslash outside quotes keeps the next character, an unquoted `#`
//! at the start of a word starts a comment. A line holding several commands (`;`, `&&`, `||`,
//! `|`, `&`) gives one example per command of the program; redirections (`> file`, `2>&1`,
//! `< in`) are dropped. Nothing is expanded: `$WORK`, `*.glb` and `{a,b}` stay words as
//! written, which is what an argument parser sees for a file name.

use std::path::{Path, PathBuf};

/// One command example: where it starts and its words, the program's name first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DocExample {
    /// The Markdown file, relative to the root given to [`doc_examples`].
    pub file: PathBuf,
    /// The 1-based line where the command starts.
    pub line: usize,
    /// The words, `words[0]` the program's name.
    pub words: Vec<String>,
}

impl std::fmt::Display for DocExample {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}", self.file.display(), self.line, self.words.join(" "))
    }
}

/// Every example of `program` in `root/README.md` and `root/docs/**/*.md` (files in name order,
/// examples in file order).
///
/// # Errors
/// When a file or folder cannot be read, or a command has an unterminated quote (the error
/// names the file and the line).
pub fn doc_examples(root: &Path, program: &str) -> std::io::Result<Vec<DocExample>> {
    let mut files = Vec::new();
    let readme = root.join("README.md");
    if readme.is_file() {
        files.push(readme);
    }
    let guide = root.join("docs");
    if guide.is_dir() {
        markdown_files(&guide, &mut files)?;
    }
    let mut out = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file)?;
        let rel = file.strip_prefix(root).unwrap_or(&file).to_path_buf();
        out.extend(
            examples_in(&text, program)
                .map_err(|(line, e)| {
                    std::io::Error::new(std::io::ErrorKind::InvalidData, format!("{}:{line}: {e}", rel.display()))
                })?
                .into_iter()
                .map(|(line, words)| DocExample { file: rel.clone(), line, words }),
        );
    }
    Ok(out)
}

/// The `.md` files under `dir`, recursively, in name order.
fn markdown_files(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)?.map(|e| e.map(|e| e.path())).collect::<Result<_, _>>()?;
    entries.sort();
    for path in entries {
        if path.is_dir() {
            markdown_files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "md") {
            out.push(path);
        }
    }
    Ok(())
}

/// What a fenced block holds.
#[derive(Clone, Copy, PartialEq)]
enum BlockKind {
    /// `sh`, `bash`, `shell`: every line is a command.
    Shell,
    /// `console`: lines starting with `$ ` are commands, the others output.
    Console,
    /// Any other language: no examples.
    Other,
}

/// A command example found in a text: its first line (1-based) and its words.
pub type LineWords = (usize, Vec<String>);

/// What is wrong with a command example: its first line (1-based) and the message.
pub type LineError = (usize, String);

/// The examples of `program` in one Markdown text. Errors carry the line.
pub fn examples_in(text: &str, program: &str) -> Result<Vec<LineWords>, LineError> {
    let mut out = Vec::new();
    // The fence of the open block and what it holds; None outside blocks.
    let mut block: Option<(String, BlockKind)> = None;
    // A command continued with `\`: its first line and the text so far.
    let mut pending: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let number = i + 1;
        let trimmed = line.trim_start();
        let Some((fence, kind)) = &block else {
            if let Some(fence) = fence_of(trimmed) {
                let info = trimmed[fence.len()..].trim();
                let kind = match info.split([' ', ',', '{']).next().unwrap_or("") {
                    "sh" | "bash" | "shell" => BlockKind::Shell,
                    "console" => BlockKind::Console,
                    _ => BlockKind::Other,
                };
                block = Some((fence, kind));
            }
            continue;
        };
        if trimmed.starts_with(fence.as_str()) && trimmed[fence.len()..].trim().is_empty() {
            if let Some((start, _)) = pending.take() {
                return Err((start, "a command continued with `\\` at the end of its block".into()));
            }
            block = None;
            continue;
        }
        let (start, command) = match (pending.take(), kind) {
            (_, BlockKind::Other) => continue,
            (Some((start, mut so_far)), _) => {
                so_far.push_str(line);
                (start, so_far)
            }
            (None, BlockKind::Console) => match trimmed.strip_prefix("$ ") {
                Some(rest) => (number, rest.to_string()),
                None => continue,
            },
            (None, BlockKind::Shell) => (number, line.to_string()),
        };
        if ends_in_continuation(&command) {
            let mut so_far = command;
            so_far.pop();
            pending = Some((start, so_far));
            continue;
        }
        for words in split_commands(&command).map_err(|e| (start, e))? {
            if words.first().is_some_and(|w| w == program) {
                out.push((start, words));
            }
        }
    }
    Ok(out)
}

/// The fence (three or more backticks or tildes) that opens a block on this line, if any.
fn fence_of(line: &str) -> Option<String> {
    let c = line.chars().next()?;
    if c != '`' && c != '~' {
        return None;
    }
    let n = line.chars().take_while(|&x| x == c).count();
    (n >= 3).then(|| std::iter::repeat_n(c, n).collect())
}

/// Whether a line ends in an unquoted, unescaped backslash (a continuation).
fn ends_in_continuation(line: &str) -> bool {
    let trailing = line.chars().rev().take_while(|&c| c == '\\').count();
    trailing % 2 == 1 && split_commands(&line[..line.len() - 1]).is_ok()
}

/// Splits one command line into commands (at unquoted `;`, `&&`, `||`, `|`, `&`), each into
/// words, dropping redirections and a trailing comment.
fn split_commands(line: &str) -> Result<Vec<Vec<String>>, String> {
    let mut commands = Vec::new();
    let mut words: Vec<String> = Vec::new();
    let mut word = String::new();
    // Whether `word` has begun (an empty quoted word `''` is a word).
    let mut in_word = false;
    // The next word is a redirection's target, to be dropped.
    let mut redirect_target = false;
    let mut chars = line.chars().peekable();
    let finish_word = |words: &mut Vec<String>, word: &mut String, in_word: &mut bool, redirect_target: &mut bool| {
        if *in_word {
            if *redirect_target {
                *redirect_target = false;
            } else {
                words.push(std::mem::take(word));
            }
            word.clear();
            *in_word = false;
        }
    };
    while let Some(c) = chars.next() {
        match c {
            '\'' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('\'') => break,
                        Some(x) => word.push(x),
                        None => return Err("unterminated single quote".into()),
                    }
                }
            }
            '"' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('"') => break,
                        Some('\\') => match chars.peek() {
                            Some(&x) if matches!(x, '"' | '\\' | '$' | '`') => {
                                word.push(x);
                                chars.next();
                            }
                            _ => word.push('\\'),
                        },
                        Some(x) => word.push(x),
                        None => return Err("unterminated double quote".into()),
                    }
                }
            }
            '\\' => {
                in_word = true;
                if let Some(x) = chars.next() {
                    word.push(x);
                }
            }
            '#' if !in_word => break,
            ' ' | '\t' => finish_word(&mut words, &mut word, &mut in_word, &mut redirect_target),
            ';' | '&' | '|' => {
                finish_word(&mut words, &mut word, &mut in_word, &mut redirect_target);
                if c != ';' && chars.peek() == Some(&c) {
                    chars.next();
                }
                commands.push(std::mem::take(&mut words));
            }
            '>' | '<' => {
                // A redirection: `>`, `>>`, `2>`, `>&2`, `2>&1`; a leading fd number is part of it.
                if in_word && word.chars().all(|d| d.is_ascii_digit()) {
                    word.clear();
                    in_word = false;
                } else {
                    finish_word(&mut words, &mut word, &mut in_word, &mut redirect_target);
                }
                if chars.peek() == Some(&c) {
                    chars.next();
                }
                if chars.peek() == Some(&'&') {
                    chars.next();
                    // `>&2`: the fd follows directly; it is the target.
                }
                redirect_target = true;
            }
            x => {
                in_word = true;
                word.push(x);
            }
        }
    }
    finish_word(&mut words, &mut word, &mut in_word, &mut redirect_target);
    commands.push(words);
    Ok(commands.into_iter().filter(|w| !w.is_empty()).collect())
}

/// Parses every `program ...` example of the docs under `root` with the command line `C` and
/// panics naming each example that does not parse (file, line, clap's message), or when no
/// example is found at all. `--help` and `--version` examples count as parsed.
pub fn assert_doc_examples_parse<C: clap::Parser>(root: &Path, program: &str) {
    let examples = doc_examples(root, program).expect("the docs are readable");
    assert!(
        !examples.is_empty(),
        "no `{program} ...` example found in {}/README.md or docs/**/*.md (```sh blocks)",
        root.display()
    );
    let failures: Vec<String> = examples
        .iter()
        .filter_map(|ex| match C::try_parse_from(&ex.words) {
            Ok(_) => None,
            // clap reports `--help` and `--version` as "errors".
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
        "{} of {} `{program}` examples do not parse:\n\n{}",
        failures.len(),
        examples.len(),
        failures.join("\n")
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(line: &str) -> Vec<Vec<String>> {
        split_commands(line).unwrap()
    }

    #[test]
    fn quotes_escapes_and_comments_split_as_a_shell_does() {
        assert_eq!(
            words(r#"surfcap a 'b c' "d \"e\" \$f" g\ h # comment"#),
            vec![vec!["surfcap", "a", "b c", "d \"e\" $f", "g h"]]
        );
        assert_eq!(words("surfcap x '' y"), vec![vec!["surfcap", "x", "", "y"]]);
        assert_eq!(words("surfcap a#b"), vec![vec!["surfcap", "a#b"]]);
        assert_eq!(words("surfcap $WORK *.glb {a,b}"), vec![vec!["surfcap", "$WORK", "*.glb", "{a,b}"]]);
    }

    #[test]
    fn operators_split_commands_and_redirections_are_dropped() {
        assert_eq!(
            words("surfcap a && surfcap b | head; x &"),
            vec![vec!["surfcap", "a"], vec!["surfcap", "b"], vec!["head"], vec!["x"]]
        );
        assert_eq!(words("surfcap a > out.txt 2>&1 b"), vec![vec!["surfcap", "a", "b"]]);
        assert_eq!(words("surfcap a 2> err.txt"), vec![vec!["surfcap", "a"]]);
    }

    #[test]
    fn blocks_continuations_and_console_prompts() {
        let md = "text surfcap no\n\n```sh\nsurfcap a \\\n  --b 'c d'\nls\n```\n\n```toml\nsurfcap = 1\n```\n\
                  ```console\n$ surfcap info x\nsurfcap not a command\n```\n````bash\nsurfcap-bench synth\n````\n";
        let found = examples_in(md, "surfcap").unwrap();
        assert_eq!(
            found,
            vec![
                (4, vec!["surfcap".into(), "a".into(), "--b".into(), "c d".into()]),
                (13, vec!["surfcap".into(), "info".into(), "x".into()])
            ]
        );
        let bench = examples_in(md, "surfcap-bench").unwrap();
        assert_eq!(bench, vec![(17, vec!["surfcap-bench".to_string(), "synth".to_string()])]);
    }

    #[test]
    fn an_unterminated_quote_names_its_line() {
        assert_eq!(examples_in("```sh\n\nsurfcap 'a\n```\n", "surfcap").unwrap_err().0, 3);
    }
}
