#!/usr/bin/env python3
"""Load time and drawing rate of the main job's page (view.html) in headless Chromium.

Load time: Utilities/browser/drive_page.js, the driver the tests use (playwright-core over
Debian's Chromium, WebGL in software through SwiftShader: no GPU), from the page's navigation
until it says the take is ready, over --repeats runs (a fresh browser each; every run must load
the take without an error). Drawing rate: the same browser, flags and window (1280 x 800); the
page is asked to show its frames one after another (dpViewer.showFrame: the morph targets
blended, normals recomputed, the mesh drawn), each followed by the browser's next animation
frame, for --seconds: frames drawn a second and ms a frame. The browser's animation frames with
nothing to draw are counted too: that rate is the ceiling (the display's, 60 a second).

    /usr/bin/python3 Testing/Benchmarks/BenchmarkPage.py [--node-tools build/tools/node]
        [--repeats 3] [--seconds 5] VIEW_HTML [VIEW_HTML ...]

Needs Debian's chromium and playwright-core in NODE_TOOLS/node_modules (Utilities/dp.sh test, or
Utilities/figures.sh, installs both).
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
DRIVER = os.path.join(ROOT, "Utilities", "browser", "drive_page.js")

# The drawing rate, in the page: its frames shown one after another, each followed by the next
# animation frame; then animation frames alone for a second (the ceiling).
DRAW = r"""
const path = require('path');
const { chromium } = require('playwright-core');
(async () => {
  const [page, seconds, flags] = process.argv.slice(2);
  const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', headless: true,
                                          args: JSON.parse(flags) });
  const report = { errors: [] };
  try {
    const tab = await browser.newPage({ viewport: { width: 1280, height: 800 } });
    tab.on('pageerror', (e) => report.errors.push(String(e)));
    await tab.goto('file://' + path.resolve(page));
    await tab.waitForFunction(
      () => window.dpViewer && (window.dpViewer.ready || window.dpViewer.error), null,
      { timeout: 180000 });
    Object.assign(report, await tab.evaluate(async (seconds) => {
      if (!dpViewer.ready) return { error: dpViewer.error };
      const next = () => new Promise((resolve) => requestAnimationFrame(resolve));
      await next();
      await next();
      let drawn = 0, inCall = 0;
      const started = performance.now();
      while (performance.now() - started < 1000 * seconds) {
        const call = performance.now();
        dpViewer.showFrame(drawn % dpViewer.frames);
        inCall += performance.now() - call;
        ++drawn;
        await next();
      }
      const ms = performance.now() - started;
      let idle = 0;
      const idleStarted = performance.now();
      while (performance.now() - idleStarted < 1000) { ++idle; await next(); }
      const idleMs = performance.now() - idleStarted;
      return { drawn, ms, inCallMs: inCall, idlePerSecond: 1000 * idle / idleMs,
               frames: dpViewer.frames, vertices: dpViewer.vertices };
    }, +seconds));
  } finally {
    await browser.close();
    process.stdout.write(JSON.stringify(report) + '\n');
  }
})().catch((e) => { console.error(String(e)); process.exit(1); });
"""


def machine():
    try:
        with open("/proc/cpuinfo") as f:
            model = next(line.split(":", 1)[1].strip() for line in f
                         if line.startswith("model name"))
    except (OSError, StopIteration):
        model = "unknown CPU"
    return f"{model}, {os.cpu_count()} hardware threads"


def driver_flags():
    """The Chromium flags of the tests' driver, read from it (one list for both)."""
    with open(DRIVER) as f:
        found = re.search(r"const FLAGS = (\[[^\]]*\]);", f.read())
    if not found:
        sys.exit(f"no FLAGS list in {DRIVER}")
    return json.loads(found.group(1).replace("'", '"').replace("\n", " "))


def node(script, args, modules, timeout=600):
    result = subprocess.run(["node", script, *args], capture_output=True, text=True,
                            timeout=timeout, env=dict(os.environ, NODE_PATH=modules))
    if result.returncode != 0:
        sys.exit(f"node {os.path.basename(script)} {' '.join(args)} failed:\n{result.stderr}")
    return json.loads(result.stdout.strip().splitlines()[-1])


def chromium_version():
    try:
        return subprocess.run(["/usr/bin/chromium", "--version"], capture_output=True, text=True,
                              timeout=60).stdout.strip()
    except OSError:
        sys.exit("/usr/bin/chromium not found (Debian's package chromium)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--node-tools", default=os.environ.get(
        "DP_NODE_TOOLS", os.path.join(ROOT, "build", "tools", "node")))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=5)
    parser.add_argument("pages", nargs="+", metavar="VIEW_HTML")
    a = parser.parse_args()
    modules = os.path.join(a.node_tools, "node_modules")
    if not os.path.isdir(os.path.join(modules, "playwright-core")):
        sys.exit(f"playwright-core not found in {modules} (Utilities/dp.sh test installs it)")
    print(f"machine: {machine()}; {chromium_version()}, headless, SwiftShader (no GPU), "
          "1280 x 800")
    flags = driver_flags()
    with tempfile.TemporaryDirectory(prefix="dp-page-bench-") as scratch:
        draw = os.path.join(scratch, "draw.js")
        with open(draw, "w") as f:
            f.write(DRAW)
        for page in a.pages:
            loads = []
            for _ in range(a.repeats):
                seen = node(DRIVER, [page], modules)
                if not seen.get("ready") or seen.get("errors"):
                    sys.exit(f"{page} did not load cleanly: {seen}")
                loads.append(seen["loadedMs"])
            drawn = node(draw, [page, str(a.seconds), json.dumps(flags)], modules)
            if "drawn" not in drawn or drawn["errors"]:
                sys.exit(f"{page}: drawing failed: {drawn}")
            print(f"\n== {page}: {os.path.getsize(page) / 1e6:.1f} MB, {drawn['frames']} "
                  f"frames of {drawn['vertices']} vertices")
            print(f"load: {statistics.median(loads) / 1000:.2f} s (median of {len(loads)} runs: "
                  f"{' / '.join(f'{ms / 1000:.2f}' for ms in loads)} s; "
                  "Utilities/browser/drive_page.js's loadedMs)")
            count, ms = drawn["drawn"], drawn["ms"]
            print(f"drawing: {1000 * count / ms:.1f} frames a second, {ms / count:.1f} ms a frame "
                  f"({count} frames shown one after another in {ms / 1000:.1f} s, "
                  f"{drawn['inCallMs'] / count:.1f} ms a frame in the page's own code; ceiling: "
                  f"{drawn['idlePerSecond']:.0f} animation frames a second with nothing to draw)")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
