// Times one ONNX model under ONNX Runtime (the CPU build inside the npm package
// onnxruntime-node) for scripts/compare_pytorch --peer ort: loads the session, runs
// --warmup untimed passes (default 1) and --runs timed passes on the input, writes every output tensor
// as raw little-endian bytes into --out-dir and prints one JSON line:
//   {"ms": [...], "outputs": {"name": {"type": "float32", "dims": [...], "file": "..."}}}
// With --profile PREFIX, ORT's own profiler writes its JSON trace (per-node times) of
// the timed passes and the line gets "profile": "<file>".
//
//   node ort_time.mjs --ort DIR --model M.onnx --input X.bin --shape 1,3,224,224
//                     --input-name input --threads 2 --runs 1 --out-dir DIR [--warmup N] [--profile PREFIX]
// DIR (--ort) is the folder holding node_modules/onnxruntime-node.
import { createRequire } from 'module';
import fs from 'fs';
import path from 'path';

function fail(msg) {
  process.stderr.write(`ort_time: ${msg}\n`);
  process.exit(1);
}

const args = {};
for (let i = 2; i < process.argv.length; i += 2) {
  const key = process.argv[i];
  if (!key.startsWith('--') || i + 1 >= process.argv.length) fail(`bad argument '${key}'`);
  args[key.slice(2)] = process.argv[i + 1];
}
for (const k of ['ort', 'model', 'input', 'shape', 'input-name', 'threads', 'runs', 'out-dir'])
  if (!(k in args)) fail(`missing --${k}`);

const ort = createRequire(path.join(path.resolve(args.ort), 'package.json'))('onnxruntime-node');
const dims = args.shape.split(',').map(Number);
const count = dims.reduce((a, b) => a * b, 1);
const bytes = fs.readFileSync(args.input);
if (bytes.length !== count * 4) fail(`${args.input}: ${bytes.length} bytes, expected ${count * 4} for [${dims}]`);
const x = new ort.Tensor('float32', new Float32Array(bytes.buffer, bytes.byteOffset, count), dims);

const options = {
  intraOpNumThreads: Number(args.threads),
  interOpNumThreads: 1,
  executionMode: 'sequential',
  graphOptimizationLevel: 'all',
};
const session = await ort.InferenceSession.create(args.model, options);
const feeds = { [args['input-name']]: x };
// Warm-up: ORT's first passes after loading are slow (ConvNeXt-Tiny 224 on AMD Zen 5, 2
// threads: 76-97 ms for the pass after the first, 43-50 ms from the third on), so a single one
// is not enough.
const warmup = 'warmup' in args ? Number(args.warmup) : 1;
if (!Number.isInteger(warmup) || warmup < 1) fail(`--warmup must be an integer >= 1, got '${args.warmup}'`);
let outputs = await session.run(feeds);
for (let i = 1; i < warmup; ++i) outputs = await session.run(feeds);
// ORT's profiler runs for the whole session once enabled; a second session with it on
// times the same passes (the first one stays unprofiled so "ms" is unperturbed).
const profiled = args.profile
  ? await ort.InferenceSession.create(args.model, { ...options, enableProfiling: true, profileFilePrefix: args.profile })
  : null;
const ms = [];
for (let i = 0; i < Number(args.runs); ++i) {
  const t0 = process.hrtime.bigint();
  outputs = await session.run(feeds);
  ms.push(Number(process.hrtime.bigint() - t0) / 1e6);
}
let profile = null;
if (profiled) {
  for (let i = 0; i < warmup; ++i) await profiled.run(feeds);  // its own warm-up
  for (let i = 0; i < Number(args.runs); ++i) await profiled.run(feeds);
  // endProfiling() returns nothing here: the trace is PREFIX_<date>.json, the newest one.
  profiled.endProfiling();
  const dir = path.dirname(path.resolve(args.profile)), base = path.basename(args.profile);
  const traces = fs.readdirSync(dir).filter((f) => f.startsWith(base) && f.endsWith('.json'))
    .map((f) => path.join(dir, f)).sort((a, b) => fs.statSync(b).mtimeMs - fs.statSync(a).mtimeMs);
  if (traces.length === 0) fail(`no profile trace ${args.profile}*.json was written`);
  profile = traces[0];
}
const described = {};
for (const [name, t] of Object.entries(outputs)) {
  const file = path.join(args['out-dir'], `${name}.bin`);
  fs.writeFileSync(file, Buffer.from(t.data.buffer, t.data.byteOffset, t.data.byteLength));
  described[name] = { type: t.type, dims: t.dims, file };
}
process.stdout.write(JSON.stringify({ ms, outputs: described, profile }) + '\n');
