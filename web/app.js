// The page: asks glint-web (the wasm module) and draws what it answers. The work is the
// library's; this file fetches files, shows images, errors and the verdict.
//
// Contract for tests and embedders (docs/features.md, "glint in the browser"):
//   await window.glintReady;
//   await window.glint.render(tomlText, { backend: "gpu" | "cpu", path })
//     -> { width, height, rgba: Uint8Array, ms }   (rgba: the bytes of `glint render`'s PNG,
//        with alpha 255; `path` names the scene in errors and anchors its files, default
//        "scenes/edited.toml")
//   window.glint.compare(a, b) -> { pixels, differing, beyondOne, maxDiff }
//   window.glint.gpuStatus     -> the adapter, or why there is no WebGPU
//   window.glint.fetchTimeoutMs (read and set; default 15000): a file the scene names that
//        does not arrive in time is given up, and the render's error says so
// A scene text over MAX_SCENE_BYTES is refused with an error naming its size; on an error
// the page keeps the last good pictures, dimmed, under the message.
import init, {
  Files,
  GpuRenderer,
  compare_rgba8,
  needed_files,
  render_cpu,
} from "./glint_web.js";

const $ = (id) => document.getElementById(id);
const DEFAULT_PATH = "scenes/edited.toml";
let files = null; // the wasm module's file table, once init() has run
const unavailable = new Map(); // path -> why its fetch failed: asked once
let fetchTimeoutMs = 15000;
// The largest scene text the page takes: the editor and the tracers run in the page's own
// thread, and a larger text is a scene for the command line.
const MAX_SCENE_BYTES = 4 << 20;
let gpu = null;
let gpuStatus = "";

// Fetches what the scene names and the page lacks, by URL relative to the page, until
// parsing asks for nothing new (an OBJ names its MTL, an MTL its textures).
async function fetchNeeded(toml, path) {
  for (let round = 0; round < 16; round++) {
    const need = needed_files(toml, path, files).filter((p) => !unavailable.has(p));
    if (need.length === 0) return;
    await Promise.all(need.map(async (p) => {
      const abort = new AbortController();
      const ms = fetchTimeoutMs;
      const timer = setTimeout(() => abort.abort(), ms);
      try {
        const r = await fetch(p, { signal: abort.signal });
        if (!r.ok) throw new Error(`HTTP ${r.status}`);
        files.add(p, new Uint8Array(await r.arrayBuffer()));
      } catch (e) {
        unavailable.set(p, abort.signal.aborted ? `no answer in ${ms / 1000} s` : String(e.message ?? e));
      } finally {
        clearTimeout(timer);
      }
    }));
  }
}

// `e` with, for each file it says the page lacks, why fetching that file failed.
function withFetchReasons(e) {
  if (e instanceof WebAssembly.RuntimeError) return e;
  let m = String(e?.message ?? e);
  for (const [p, why] of unavailable) {
    if (m.includes(`${p} is not loaded`)) m += ` (fetching ${p}: ${why})`;
  }
  return new Error(m);
}

async function render(toml, options = {}) {
  const backend = options.backend ?? "gpu";
  const path = options.path ?? DEFAULT_PATH;
  const bytes = new TextEncoder().encode(toml).length;
  if (bytes > MAX_SCENE_BYTES) {
    throw new Error(`${path}: the scene text is ${(bytes / 2 ** 20).toFixed(1)} MiB; the page ` +
      `takes scenes up to ${MAX_SCENE_BYTES / 2 ** 20} MiB (glint render has no such limit)`);
  }
  await fetchNeeded(toml, path);
  let r;
  try {
    if (backend === "cpu") {
      r = render_cpu(toml, path, files);
    } else if (backend === "gpu") {
      if (!gpu) throw new Error(gpuStatus);
      r = await gpu.render(toml, path, files);
    } else {
      throw new Error(`unknown backend ${JSON.stringify(backend)}: "gpu" or "cpu"`);
    }
  } catch (e) {
    throw withFetchReasons(e);
  }
  const out = { width: r.width, height: r.height, rgba: r.rgba, ms: r.ms };
  r.free();
  return out;
}

function compare(a, b) {
  const c = compare_rgba8(a.rgba, b.rgba, a.width, a.height);
  const out = {
    pixels: c.pixels,
    differing: c.differing,
    beyondOne: c.beyond_one,
    maxDiff: c.max_diff,
    map: c.map,
  };
  c.free();
  return out;
}

function draw(canvas, width, height, rgba) {
  canvas.width = width;
  canvas.height = height;
  const ctx = canvas.getContext("2d");
  ctx.putImageData(new ImageData(new Uint8ClampedArray(rgba), width, height), 0, 0);
}

function clear(canvas) {
  canvas.width = 1;
  canvas.height = 1;
}

// An error's text for the page: a trap in the wasm is a panic, whose message went to the
// console (the crate's panic hook).
function message(e) {
  const m = String(e?.message ?? e);
  return e instanceof WebAssembly.RuntimeError
    ? `glint panicked (${m}), a defect: the browser's console has its message`
    : m;
}

// One render of the editor's text on both tracers; a newer edit supersedes an older one.
let generation = 0;
async function update() {
  const mine = ++generation;
  const toml = $("editor").value;
  const path = `scenes/${$("scene").value || "edited"}.toml`;
  let cpu = null, gpuImage = null, error = "";
  try {
    cpu = await render(toml, { backend: "cpu", path });
  } catch (e) {
    error = message(e);
  }
  if (mine !== generation) return;
  if (cpu && gpu) {
    try {
      gpuImage = await render(toml, { backend: "gpu", path });
    } catch (e) {
      error = `GPU: ${message(e)}`;
    }
  }
  if (mine !== generation) return;
  $("error").textContent = error;
  // Where a render failed, its last good picture stays, dimmed.
  $("cpu-image").classList.toggle("stale", !cpu);
  $("gpu-image").classList.toggle("stale", gpu !== null && !gpuImage);
  $("diff-image").classList.toggle("stale", error !== "");
  if (cpu) {
    draw($("cpu-image"), cpu.width, cpu.height, cpu.rgba);
    $("cpu-time").textContent = `${cpu.ms.toFixed(1)} ms`;
  } else {
    $("cpu-time").textContent = "(the last good picture)";
  }
  if (gpuImage) {
    draw($("gpu-image"), gpuImage.width, gpuImage.height, gpuImage.rgba);
    $("gpu-time").textContent = `${gpuImage.ms.toFixed(1)} ms`;
  } else if (!gpu) {
    clear($("gpu-image"));
    $("gpu-time").textContent = "(no WebGPU)";
  } else {
    $("gpu-time").textContent = "(the last good picture)";
  }
  const verdict = $("verdict");
  if (error) {
    verdict.textContent = "";
    verdict.className = "";
  } else if (cpu && gpuImage) {
    const c = compare(gpuImage, cpu);
    draw($("diff-image"), cpu.width, cpu.height, c.map);
    if (c.differing === 0) {
      verdict.textContent = "GPU = CPU in every bit";
      verdict.className = "same";
    } else {
      const pct = (100 * c.differing / c.pixels).toPrecision(2);
      verdict.textContent =
        `GPU ≠ CPU: ${c.differing} of ${c.pixels} pixels differ (${pct} %), ` +
        `${c.beyondOne} by more than 1/255, at most ${c.maxDiff}/255`;
      verdict.className = "differ";
    }
  } else {
    clear($("diff-image"));
    verdict.textContent = "CPU image only (no GPU image to compare)";
    verdict.className = "";
  }
}

let timer = 0;
function edited() {
  clearTimeout(timer);
  timer = setTimeout(update, 250);
}

async function pick() {
  const name = $("scene").value;
  const r = await fetch(`scenes/${name}.toml`);
  $("editor").value = r.ok ? await r.text() : `# scenes/${name}.toml: HTTP ${r.status}`;
  await update();
}

async function main() {
  await init();
  files = new Files();
  try {
    if (!navigator.gpu) throw new Error("this browser has no WebGPU (navigator.gpu is missing)");
    gpu = await GpuRenderer.open();
    gpuStatus = gpu.describe();
  } catch (e) {
    gpu = null;
    gpuStatus = `${e.message ?? e}: only the CPU image is shown. WebGPU is in Chrome and ` +
      "Edge 113+, Safari 26+ and Firefox 141+ (Windows; elsewhere behind a setting).";
  }
  $("webgpu").textContent = gpuStatus;
  window.glint = {
    render,
    compare: (a, b) => {
      const { map, ...counts } = compare(a, b);
      return counts;
    },
    get gpuStatus() { return gpuStatus; },
    get fetchTimeoutMs() { return fetchTimeoutMs; },
    set fetchTimeoutMs(ms) { fetchTimeoutMs = ms; },
    hasGpu: gpu !== null,
  };
  const index = await (await fetch("scenes/index.json")).json();
  for (const name of index.scenes) {
    const o = document.createElement("option");
    o.value = o.textContent = name;
    $("scene").append(o);
  }
  $("scene").value = index.scenes.includes("bb8") ? "bb8" : index.scenes[0];
  $("scene").addEventListener("change", pick);
  $("editor").addEventListener("input", edited);
  await pick();
  window.glintReadyResolve();
}

main().catch((e) => {
  $("error").textContent = `glint could not start: ${e.message ?? e}`;
  window.glintReadyReject(e);
});
