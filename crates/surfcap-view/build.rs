//! Installs three.js from the npm registry (pinned by web/package-lock.json) when it is not
//! there yet, so the viewer's assets can be embedded with `include_str!` and the page works
//! offline. Needs `npm` at build time (the README's commands install Node.js and npm).

use std::path::Path;
use std::process::Command;

fn main() {
    println!("cargo:rerun-if-changed=web/package-lock.json");
    println!("cargo:rerun-if-changed=web/node_modules/three/package.json");
    let web = Path::new(env!("CARGO_MANIFEST_DIR")).join("web");
    if web.join("node_modules/three/build/three.module.js").is_file() {
        return;
    }
    let status = Command::new("npm")
        .args(["ci", "--no-audit", "--no-fund", "--loglevel=error"])
        .current_dir(&web)
        .status()
        .unwrap_or_else(|e| {
            panic!(
                "surfcap-view embeds three.js from npm: running `npm ci` in {} failed ({e}); install Node.js and npm (Debian: apt-get install nodejs npm) and build again",
                web.display()
            )
        });
    assert!(status.success(), "`npm ci` in {} failed ({status}): three.js could not be installed", web.display());
}
