//! The viewer's page in headless Chromium, driven through the Chrome DevTools Protocol
//! (`headless_chrome`): the page's script contract (`surfcap-view`'s `viewer.js`) is
//! `window.surfcapViewer = { ready, nFrames, fps, setFrame(i), setView(preset), ... }`, set once
//! every item is loaded; `setFrame(i)` pauses, shows frame `i` and renders it synchronously.
//! The page is opened with `?ui=0` (the bare scene: no panel, legend or timeline) and, when
//! asked, `&view=<preset>`.
//!
//! Sizes are exact: the viewport is set to `width x height` CSS pixels at a device scale factor
//! of 1 (`Emulation.setDeviceMetricsOverride`), so every screenshot has that many pixels.
//! WebGL runs on SwiftShader (software), as in the project's browser tests, so no GPU is needed.

use std::ffi::OsStr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use headless_chrome::protocol::cdp::{Emulation, Page as Cdp, Runtime};
use headless_chrome::{Browser, LaunchOptions, Tab};

use crate::{RenderError, Rgba};

/// How to open the page.
#[derive(Debug, Clone)]
pub struct PageOptions {
    /// The Chromium (or Chrome) executable.
    pub chromium: PathBuf,
    pub width: u32,
    pub height: u32,
    /// A view preset the page knows (`top`, `front`, `side`, `three-quarter`, `follow`), or the
    /// page's own framing.
    pub view: Option<String>,
    /// Longest wait for the page to load every item and for any one frame.
    pub timeout: Duration,
}

/// The page, loaded and ready: its animation's frame count and rate.
pub struct Page {
    // Kept alive with the tab: dropping it ends the Chromium process.
    _browser: Browser,
    tab: Arc<Tab>,
    url: String,
    pub n_frames: usize,
    pub fps: f64,
    pub width: u32,
    pub height: u32,
}

/// The largest side Chromium is asked to render (a screenshot of more pixels is refused).
pub const MAX_SIDE: u32 = 8192;

/// Whether this process runs as root, where Chromium refuses its sandbox.
fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() == 0 }
}

impl Page {
    /// Starts Chromium, opens the viewer at `base_url` (`http://127.0.0.1:PORT/`) with its bare
    /// scene, and waits until every item is loaded.
    pub fn open(base_url: &str, opts: &PageOptions) -> Result<Page, RenderError> {
        if !opts.chromium.is_file() {
            return Err(RenderError::ChromiumMissing(opts.chromium.clone()));
        }
        if opts.width == 0 || opts.height == 0 || opts.width > MAX_SIDE || opts.height > MAX_SIDE {
            return Err(RenderError::Size(opts.width, opts.height, format!("expected 1 to {MAX_SIDE} pixels a side")));
        }
        let mut url = format!("{}/?ui=0", base_url.trim_end_matches('/'));
        if let Some(v) = &opts.view {
            url.push_str(&format!("&view={v}"));
        }
        let page_error = |why: String| RenderError::Page(url.clone(), why);
        let args: Vec<&OsStr> = [
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--ignore-gpu-blocklist",
            "--force-device-scale-factor=1",
            "--hide-scrollbars",
            "--mute-audio",
        ]
        .iter()
        .map(OsStr::new)
        .collect();
        let launch = LaunchOptions {
            headless: true,
            sandbox: !is_root(),
            path: Some(opts.chromium.clone()),
            window_size: Some((opts.width, opts.height)),
            idle_browser_timeout: opts.timeout + Duration::from_secs(30),
            args,
            ..LaunchOptions::default()
        };
        let start = |e: anyhow::Error| RenderError::ChromiumStart(opts.chromium.clone(), format!("{e:#}"));
        let browser = Browser::new(launch).map_err(start)?;
        let tab = browser.new_tab().map_err(start)?;
        tab.set_default_timeout(opts.timeout);
        tab.call_method(Emulation::SetDeviceMetricsOverride {
            width: opts.width,
            height: opts.height,
            device_scale_factor: 1.0,
            mobile: false,
            scale: None,
            screen_width: None,
            screen_height: None,
            position_x: None,
            position_y: None,
            dont_set_visible_size: None,
            screen_orientation: None,
            viewport: None,
            display_feature: None,
            device_posture: None,
        })
        .map_err(|e| page_error(format!("could not set the size: {e:#}")))?;
        // The navigation's wait uses the tab's default timeout (20 s in headless_chrome): a
        // loaded machine takes longer, so the user's --timeout bounds it as every other wait.
        tab.set_default_timeout(opts.timeout);
        tab.navigate_to(&url)
            .and_then(|t| t.wait_until_navigated())
            .map_err(|e| page_error(format!("could not load: {e:#}")))?;
        // Ready when the contract says so; the page's own error line (items that could not be
        // loaded) ends the wait early with its message.
        let wait = format!(
            r#"new Promise((resolve, reject) => {{
                const t0 = performance.now();
                const check = () => {{
                    const v = window.surfcapViewer, e = document.getElementById('error');
                    if (e && e.textContent) return reject(new Error(e.textContent));
                    if (v && v.ready) return resolve(JSON.stringify({{ nFrames: v.nFrames, fps: v.fps }}));
                    if (performance.now() - t0 > {ms}) return reject(new Error('not ready after {s} s (window.surfcapViewer.ready never became true)'));
                    setTimeout(check, 25);
                }};
                check();
            }})"#,
            ms = opts.timeout.as_millis(),
            s = opts.timeout.as_secs()
        );
        let ready = evaluate(&tab, &wait).map_err(&page_error)?;
        let v: serde_json::Value = serde_json::from_str(ready.as_str().unwrap_or(""))
            .map_err(|e| page_error(format!("unreadable state: {e}")))?;
        let n_frames = v["nFrames"].as_u64().filter(|&n| n > 0);
        let fps = v["fps"].as_f64().filter(|f| f.is_finite() && *f > 0.0);
        let (Some(n_frames), Some(fps)) = (n_frames, fps) else {
            return Err(page_error(format!("expected nFrames > 0 and fps > 0 from window.surfcapViewer, got {v}")));
        };
        Ok(Page {
            _browser: browser,
            tab,
            url,
            n_frames: n_frames as usize,
            fps,
            width: opts.width,
            height: opts.height,
        })
    }

    /// Frame `f` of the animation, as the page draws it.
    pub fn frame(&self, f: usize) -> Result<Rgba, RenderError> {
        let frame_error = |why: String| RenderError::Frame { frame: f, why };
        // setFrame renders synchronously; waiting one animation frame lets the compositor take
        // the new canvas before the screenshot.
        let show = format!(
            "new Promise((resolve) => {{ window.surfcapViewer.setFrame({f}); requestAnimationFrame(() => resolve(true)); }})"
        );
        evaluate(&self.tab, &show).map_err(frame_error)?;
        let shot = self
            .tab
            .capture_screenshot(Cdp::CaptureScreenshotFormatOption::Png, None, None, true)
            .map_err(|e| frame_error(format!("screenshot failed: {e:#}")))?;
        let image = image::load_from_memory_with_format(&shot, image::ImageFormat::Png)
            .map_err(|e| frame_error(format!("unreadable screenshot: {e}")))?
            .into_rgba8();
        if image.width() != self.width || image.height() != self.height {
            return Err(frame_error(format!(
                "screenshot of {}x{} pixels, expected {}x{}",
                image.width(),
                image.height(),
                self.width,
                self.height
            )));
        }
        Ok(Rgba { width: self.width, height: self.height, data: image.into_raw() })
    }

    /// The page's address.
    pub fn url(&self) -> &str {
        &self.url
    }
}

/// Evaluates `expression` in the page (awaiting a promise), returning its value; a thrown error
/// or a rejected promise is returned as its message.
fn evaluate(tab: &Tab, expression: &str) -> Result<serde_json::Value, String> {
    let r = tab
        .call_method(Runtime::Evaluate {
            expression: expression.to_string(),
            object_group: None,
            include_command_line_api: None,
            silent: None,
            context_id: None,
            return_by_value: Some(true),
            generate_preview: None,
            user_gesture: None,
            await_promise: Some(true),
            throw_on_side_effect: None,
            timeout: None,
            disable_breaks: None,
            repl_mode: None,
            allow_unsafe_eval_blocked_by_csp: None,
            unique_context_id: None,
            serialization_options: None,
        })
        .map_err(|e| format!("{e:#}"))?;
    if let Some(x) = r.exception_details {
        let message = x.exception.and_then(|e| e.description).unwrap_or(x.text);
        return Err(message.lines().next().unwrap_or("").to_string());
    }
    Ok(r.result.value.unwrap_or(serde_json::Value::Null))
}
