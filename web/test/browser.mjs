// Drives the built page (web/dist) in headless Chromium with WebGPU, through the DevTools
// protocol (Node's built-in WebSocket: run with `node --experimental-websocket` on Node 20),
// for tests/browser.rs. Nothing is installed from npm.
//
//     node --experimental-websocket web/test/browser.mjs DIST OUT < requests.json
//
// requests.json: [{ "name", "toml", "path", "backend": "cpu" | "gpu" }    a render
//                 { "name", "edit": "toml text" }                        the page's editor
//                 { "name", "screenshot": true }]                        a PNG of the page
// Writes OUT/NAME.rgba (a render's bytes), OUT/NAME.png (a screenshot) and OUT/results.json:
// { gpuStatus, hasGpu, userAgent, results: { NAME: { width, height, ms } | { error }
//   | { shownError, verdict } | { screenshot } } }.
// Exit status: 0 once every request has an answer (a render's own error is an answer),
// 1 when the page or the browser fails, or no request is answered for 240 s. Each answer is
// logged on stderr as it comes (name, milliseconds).
import { spawn } from "node:child_process";
import { createServer } from "node:http";
import { mkdtempSync, readFileSync, rmSync, writeFileSync, statSync } from "node:fs";
import { tmpdir } from "node:os";
import { extname, join, normalize, resolve } from "node:path";

const [dist, out] = process.argv.slice(2);
if (!dist || !out) {
  console.error("usage: node --experimental-websocket web/test/browser.mjs DIST OUT < requests.json");
  process.exit(2);
}
const requests = JSON.parse(readFileSync(0, "utf8"));
const chromium = process.env.GLINT_CHROMIUM ?? "chromium";

const TYPES = {
  ".html": "text/html", ".js": "text/javascript", ".mjs": "text/javascript",
  ".wasm": "application/wasm", ".json": "application/json", ".css": "text/css",
  ".png": "image/png", ".jpg": "image/jpeg", ".toml": "text/plain",
};
const root = resolve(dist);
// A URL under /never/ is never answered: a server that hangs, for the page's fetch timeout.
const server = createServer((req, res) => {
  if (new URL(req.url, "http://x").pathname.startsWith("/never/")) return;
  const path = normalize(join(root, decodeURIComponent(new URL(req.url, "http://x").pathname)));
  let file = path;
  try {
    if (!path.startsWith(root)) throw new Error("outside");
    if (statSync(file).isDirectory()) file = join(file, "index.html");
    const body = readFileSync(file);
    res.writeHead(200, { "content-type": TYPES[extname(file)] ?? "application/octet-stream" });
    res.end(body);
  } catch {
    res.writeHead(404).end();
  }
});
await new Promise((r) => server.listen(0, "127.0.0.1", r));
const url = `http://127.0.0.1:${server.address().port}/`;

const profile = mkdtempSync(join(tmpdir(), "glint-chromium-"));
const browser = spawn(chromium, [
  "--headless=new", "--no-sandbox", "--enable-unsafe-webgpu",
  "--no-first-run", "--disable-background-networking", "--disable-component-update",
  "--disable-sync", "--disable-quic", "--disable-default-apps",
  `--user-data-dir=${profile}`, "--remote-debugging-port=0", "--window-size=1500,950",
  "about:blank",
], { stdio: ["ignore", "ignore", "pipe"] });
let log = "";
const consoleLines = [];
const failed = (why) => {
  console.error(`browser.mjs: ${why}`);
  if (consoleLines.length) console.error(`the page's console:\n${consoleLines.join("\n")}`);
  if (log) console.error(`chromium said:\n${log.slice(-4000)}`);
  finish(1);
};
function finish(code) {
  try { browser.kill("SIGKILL"); } catch {}
  server.closeAllConnections();
  server.close();
  try { rmSync(profile, { recursive: true, force: true }); } catch {}
  process.exit(code);
}
// A watchdog that each answer restarts: a hang fails, a slow but moving session does not.
let waitingFor = "the page";
let watchdog;
const restartWatchdog = () => {
  clearTimeout(watchdog);
  watchdog = setTimeout(() => failed(`no answer within 240 s (waiting for ${waitingFor})`), 240_000);
  watchdog.unref();
};
restartWatchdog();
browser.on("exit", (code) => failed(`chromium exited (${code})`));

const wsBrowser = await new Promise((res) => {
  browser.stderr.on("data", (d) => {
    log += d;
    const m = log.match(/DevTools listening on (ws:\/\/\S+)/);
    if (m) res(m[1]);
  });
});
const port = new URL(wsBrowser).port;
const target = await (await fetch(`http://127.0.0.1:${port}/json/new?${url}`, { method: "PUT" })).json();

const ws = new WebSocket(target.webSocketDebuggerUrl);
await new Promise((r, j) => { ws.onopen = r; ws.onerror = () => j(new Error("DevTools socket")); });
let nextId = 0;
const pending = new Map();
ws.onmessage = (ev) => {
  const m = JSON.parse(ev.data);
  if (m.id !== undefined && pending.has(m.id)) {
    pending.get(m.id)(m);
    pending.delete(m.id);
  } else if (m.method === "Runtime.consoleAPICalled") {
    consoleLines.push(m.params.args.map((a) => a.value ?? a.description ?? "").join(" "));
  } else if (m.method === "Log.entryAdded") {
    consoleLines.push(`${m.params.entry.level}: ${m.params.entry.text}`);
  } else if (m.method === "Runtime.exceptionThrown") {
    consoleLines.push(`exception: ${m.params.exceptionDetails.exception?.description ?? m.params.exceptionDetails.text}`);
  }
};
const send = (method, params = {}) => new Promise((res, rej) => {
  const id = ++nextId;
  pending.set(id, (m) => (m.error ? rej(new Error(`${method}: ${m.error.message}`)) : res(m.result)));
  ws.send(JSON.stringify({ id, method, params }));
});
// Evaluates an async expression in the page; its value (JSON-able) or a thrown error.
async function evaluate(expression) {
  const r = await send("Runtime.evaluate", { expression, awaitPromise: true, returnByValue: true });
  if (r.exceptionDetails) {
    throw new Error(r.exceptionDetails.exception?.description ?? r.exceptionDetails.text);
  }
  return r.result.value;
}

try {
  await send("Runtime.enable");
  await send("Log.enable");
  await send("Emulation.setDeviceMetricsOverride", { width: 1500, height: 950, deviceScaleFactor: 1, mobile: false });
  // Wait for the contract to exist, then for the page to be ready.
  const deadline = Date.now() + 120_000;
  while (!(await evaluate("typeof window.glintReady === 'object'"))) {
    if (Date.now() > deadline) throw new Error("window.glintReady never appeared");
    const thrown = consoleLines.find((l) => l.startsWith("exception: "));
    if (thrown) throw new Error(`the page threw before it was ready: ${thrown}`);
    await new Promise((r) => setTimeout(r, 100));
  }
  await evaluate("window.glintReady.then(() => true)");
} catch (e) {
  failed(`the page did not become ready: ${e.message}\nconsole:\n${consoleLines.join("\n")}`);
}

console.error("browser.mjs: the page is ready");
const info = await evaluate("({ gpuStatus: glint.gpuStatus, hasGpu: glint.hasGpu, userAgent: navigator.userAgent })");
const results = {};
for (const q of requests) {
  waitingFor = q.name;
  restartWatchdog();
  const t0 = Date.now();
  try {
    if (q.screenshot) {
      await evaluate("new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)))");
      const shot = await send("Page.captureScreenshot", { format: "png" });
      writeFileSync(join(out, `${q.name}.png`), Buffer.from(shot.data, "base64"));
      results[q.name] = { screenshot: `${q.name}.png` };
    } else if (q.edit !== undefined) {
      // Type into the editor as a user would (an input event), then wait for the page's
      // answer: the error under the editor, or the verdict, whichever changes; with the
      // CPU picture's size and whether it is dimmed as stale, and the seconds it took.
      results[q.name] = await evaluate(`(async () => {
        ${q.fetchTimeoutMs !== undefined ? `glint.fetchTimeoutMs = ${q.fetchTimeoutMs};` : ""}
        const ed = document.getElementById("editor");
        document.getElementById("error").textContent = "";
        document.getElementById("verdict").textContent = "";
        ed.value = ${JSON.stringify(q.edit)} + ("# " + "x".repeat(77) + "\\n").repeat(${Math.ceil((q.pad ?? 0) / 80)});
        ed.dispatchEvent(new Event("input"));
        const t0 = performance.now();
        while (performance.now() - t0 < 60000) {
          await new Promise((r) => setTimeout(r, 50));
          const shownError = document.getElementById("error").textContent;
          const verdict = document.getElementById("verdict").textContent;
          if (shownError || verdict) {
            const c = document.getElementById("cpu-image");
            return { shownError, verdict, cpuSize: [c.width, c.height],
              stale: c.classList.contains("stale"), seconds: (performance.now() - t0) / 1000 };
          }
        }
        return { shownError: "", verdict: "", timedOut: true };
      })()`);
    } else {
      const r = await evaluate(`(async () => {
        try {
          const r = await glint.render(${JSON.stringify(q.toml)},
            { backend: ${JSON.stringify(q.backend)}, path: ${JSON.stringify(q.path)} });
          let s = "";
          for (let i = 0; i < r.rgba.length; i += 0x8000) {
            s += String.fromCharCode.apply(null, r.rgba.subarray(i, i + 0x8000));
          }
          return { width: r.width, height: r.height, ms: r.ms, isBytes: r.rgba instanceof Uint8Array, b64: btoa(s) };
        } catch (e) {
          return { error: String(e.message ?? e) };
        }
      })()`);
      if (r.b64 !== undefined) {
        writeFileSync(join(out, `${q.name}.rgba`), Buffer.from(r.b64, "base64"));
        delete r.b64;
      }
      results[q.name] = r;
    }
  } catch (e) {
    results[q.name] = { error: `driver: ${e.message}` };
  }
  console.error(`browser.mjs: ${q.name}: ${Date.now() - t0} ms${results[q.name]?.error ? ` (error: ${results[q.name].error})` : ""}`);
}
writeFileSync(join(out, "results.json"), JSON.stringify({ ...info, results, console: consoleLines }, null, 1));
finish(0);
