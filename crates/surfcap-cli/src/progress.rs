//! Progress bars (indicatif) behind the library's `Progress` hooks. Bars go to stderr, appear
//! only when it is a terminal, and are off with `--quiet` or `--json`.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use surfcap_mesh::Progress;

pub struct Bar {
    bar: ProgressBar,
    /// Whether the library's notes are shown (as `Ctx::note` shows them).
    notes: bool,
}

impl Bar {
    pub fn new(ctx: &crate::Ctx) -> Self {
        let target = if ctx.quiet || ctx.json { ProgressDrawTarget::hidden() } else { ProgressDrawTarget::stderr() };
        let bar = ProgressBar::with_draw_target(Some(0), target);
        bar.set_style(
            ProgressStyle::with_template("{msg:28} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta})")
                .expect("static template is valid"),
        );
        Bar { bar, notes: !ctx.quiet && !ctx.json }
    }
}

impl Progress for Bar {
    fn start(&self, label: &str, total: u64) {
        self.bar.reset();
        self.bar.set_length(total);
        self.bar.set_message(label.to_string());
    }
    fn advance(&self, n: u64) {
        self.bar.inc(n);
    }
    fn finish(&self) {
        self.bar.finish_and_clear();
    }
    fn note(&self, text: &str) {
        if self.notes {
            self.bar.suspend(|| eprintln!("note: {text}"));
        }
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
