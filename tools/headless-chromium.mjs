// Headless Chromium for the tools' browser checks (browser-test.mjs, played-test.mjs,
// play-page.mjs): Debian's /usr/bin/chromium, or the one $CHROMIUM names, driven by
// playwright-core, with WebGL drawn by SwiftShader (software rendering), since the machines the
// tests run on have no GPU. One place for the launch, so that every tool runs the same browser.
import { chromium } from 'playwright-core';

// The browser, launched; the caller closes it.
export function launchChromium() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
}
