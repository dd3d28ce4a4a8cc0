#include "dashboard.h"

#include <string>

namespace pf::master {

namespace {

// The preview is position: fixed, so it stays in view beside long job lists; the header has a fixed
// height so that nothing above it moves the frame.
std::string previewCss() {
    const std::string side = std::to_string(kPreviewFramePx) + "px";
    return "#preview { position: fixed; top: " + std::to_string(kPreviewFrameTopPx) +
           "px; right: " + std::to_string(kPreviewFrameRightPx) + "px; width: " + side +
           "; }\n"
           "#preview .frame { width: " +
           side + "; height: " + side +
           "; background: #15191e; display: flex; align-items: center; justify-content: center; }\n"
           "main { margin-right: " +
           std::to_string(kPreviewFramePx + 2 * kPreviewFrameRightPx) + "px; }\n";
}

constexpr const char *kHead = R"html(<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>pathfarm</title>
<style>
:root { --fg: #1d232a; --muted: #6b7480; --line: #e3e6ea; --accent: #2f6fdb; }
* { box-sizing: border-box; }
body { font: 14px/1.4 system-ui, "DejaVu Sans", sans-serif; margin: 0; background: #f4f5f7; color: var(--fg); }
header { height: 48px; display: flex; align-items: center; gap: 2em; padding: 0 24px; background: #1d232a; color: #fff; }
header h1 { font-size: 17px; margin: 0; font-weight: 600; }
#summary span { margin-right: 1.6em; color: #aeb8c4; } #summary b { color: #fff; font-weight: 600; }
main { padding: 24px; }
section { background: #fff; border: 1px solid var(--line); border-radius: 6px; padding: 8px 10px; margin-bottom: 20px; overflow-x: auto; }
h2 { font-size: 15px; margin: 2px 0 8px; }
table { border-collapse: collapse; width: 100%; font-size: 13px; }
th { text-align: left; font-weight: 600; color: var(--muted); font-size: 12px; }
td, th { padding: 4px 6px; border-bottom: 1px solid var(--line); white-space: nowrap; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
tbody tr:last-child td { border-bottom: none; }
tr.job { cursor: pointer; } tr.job:hover { background: #f7f9fc; } tr.job.selected { background: #eaf1ff; }
.empty { color: var(--muted); padding: 8px; }
.state { padding: 1px 8px; border-radius: 9px; font-size: 12px; background: #e6e8eb; color: #46505c; }
.state.running, .state.busy { background: #dbe8ff; color: #1b4fa8; }
.state.done, .state.idle { background: #dcf3e3; color: #1e6b35; }
.state.failed, .state.lost { background: #fde0e0; color: #a12020; }
.state.draining { background: #fff1d6; color: #8a5a00; }
.bar { display: inline-block; vertical-align: middle; width: 72px; height: 9px; background: var(--line); border-radius: 5px; overflow: hidden; margin-right: 6px; }
.bar > div { height: 100%; background: var(--accent); }
.muted { color: var(--muted); }
#preview img { width: 100%; height: 100%; object-fit: contain; display: none; }
#preview.loaded img { display: block; } #preview.loaded .placeholder { display: none; }
#preview .placeholder { color: #8a94a0; }
#preview figcaption { margin-top: 8px; } #preview .acceptance { font-size: 12px; color: var(--muted); margin-top: 4px; }
)html";

constexpr const char *kBody = R"html(</style></head>
<body>
<header><h1>pathfarm</h1><div id="summary"></div></header>
<main>
<section><h2>Jobs</h2>
<table id="jobs"><thead><tr><th>job</th><th>state</th><th>integrator</th><th>progress</th><th class="num">samples</th>
<th class="num">merged</th><th class="num">rate</th><th class="num">acceptance</th><th class="num">elapsed</th></tr></thead>
<tbody></tbody></table></section>
<section><h2>Workers</h2>
<table id="workers"><thead><tr><th>worker</th><th>host</th><th>state</th><th class="num">threads/cores</th><th class="num">leases</th>
<th class="num">tasks done</th><th class="num">failed</th><th class="num">rate</th><th class="num">last seen</th><th>version</th></tr></thead>
<tbody></tbody></table></section>
</main>
<aside id="preview"><div class="frame"><img alt="live preview"><span class="placeholder">no image yet</span></div>
<figcaption></figcaption><div class="acceptance"></div></aside>
<script>
'use strict';
const short = s => (s || '').replace(/^(JOB|WORKER|CHAIN_PHASE)_/, '').toLowerCase();
const num = v => Number(v || 0);
function si(v) {
  for (const [d, u] of [[1e12, 'T'], [1e9, 'G'], [1e6, 'M'], [1e3, 'k']]) if (v >= d) return (v / d).toPrecision(3) + u;
  return String(Math.round(v));
}
function clock(s) {
  s = Math.floor(s);
  const h = Math.floor(s / 3600), m = Math.floor(s / 60) % 60, r = String(s % 60).padStart(2, '0');
  return h > 0 ? h + ':' + String(m).padStart(2, '0') + ':' + r : m + ':' + r;
}
function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined) e.textContent = text;
  return e;
}
function row(cells) {
  const tr = el('tr');
  for (const c of cells) {
    const td = el('td');
    if (c instanceof Node) td.appendChild(c); else td.textContent = String(c);
    tr.appendChild(td);
  }
  return tr;
}
function numeric(tr, from) { [...tr.children].forEach((td, i) => { if (from.includes(i)) td.className = 'num'; }); return tr; }
function badge(state) { return el('span', 'state ' + short(state), short(state)); }
function progress(p) {
  const wrap = el('span'), b = el('div', 'bar'), f = el('div');
  f.style.width = (100 * p).toFixed(1) + '%';
  b.appendChild(f); wrap.appendChild(b); wrap.appendChild(document.createTextNode((100 * p).toFixed(0) + '%'));
  return wrap;
}
// Acceptance of a chain job over all mutation types, and per type for the caption.
function acceptance(j) {
  const counts = (j.chain && j.chain.mutation_counts) || [];
  let p = 0, a = 0;
  for (const c of counts) { p += num(c.proposed); a += num(c.accepted); }
  return { overall: p > 0 ? (100 * a / p).toFixed(1) + '%' : '', types: counts.filter(c => num(c.proposed) > 0)
    .map(c => c.name + ' ' + (100 * num(c.accepted) / num(c.proposed)).toFixed(1) + '%').join(' · ') };
}
function samplesCell(j) { return j.chain ? si(num(j.chain.mutations)) + ' mut' : num(j.samples_per_pixel) + ' spp'; }
// A chain job's seeding and direct component, in pixel samples (its chains are in mutations).
function chainSamples(j) {
  return j.chain ? ' · seeding ' + si(num(j.chain.seeding_samples)) + ' spl · direct ' +
    si(num(j.chain.direct_samples)) + ' spl' : '';
}
// A worker's rates in their units: pixel samples (image and seeding tasks), mutations (chain tasks).
function workerRate(w) {
  const m = num(w.mutations_per_second);
  return si(num(w.samples_per_second)) + ' spl/s' + (m > 0 ? ' · ' + si(m) + ' mut/s' : '');
}
// A chain job's phase beside its state: its image only exists once the chains run.
function stateCell(j) {
  const cell = el('span');
  cell.appendChild(badge(j.state));
  if (j.chain && short(j.state) === 'running') cell.appendChild(el('span', 'muted', ' ' + short(j.chain.phase)));
  return cell;
}
const seeding = j => j.chain && short(j.chain.phase) === 'seeding';
function rate(j) {
  const s = num(j.render_seconds);
  if (s <= 0) return '';
  return j.chain ? si(num(j.chain.mutations) / s) + ' mut/s' : si(num(j.samples) / s) + ' spl/s';
}

let pinned = null, shownKey = null;
function showPreview(j) {
  const box = document.getElementById('preview');
  const acc = acceptance(j);
  box.querySelector('figcaption').textContent = 'Job ' + j.id + ' · ' + short(j.state) + ' · ' + j.width + '×' +
    j.height + ' · ' + samplesCell(j) + chainSamples(j) + ' · ' + clock(num(j.render_seconds));
  box.querySelector('.acceptance').textContent = acc.types ? 'acceptance: ' + acc.types : '';
  const key = j.id + '/' + j.tasks.merged + '/' + j.state;
  if (seeding(j)) {
    box.classList.remove('loaded');
    box.querySelector('.placeholder').textContent = 'seeding the chains';
    shownKey = null;
    return;
  }
  if (key === shownKey || num(j.tasks.merged) === 0) return;
  shownKey = key;
  // Load the next image off screen and swap it in, so that the preview never flashes empty.
  const next = new Image();
  next.onload = () => {
    const img = box.querySelector('img');
    img.src = next.src;
    img.style.imageRendering = next.naturalWidth * 2 <= box.clientWidth ? 'pixelated' : 'auto';
    box.classList.add('loaded');
  };
  next.src = '/api/v1/jobs/' + j.id + '/preview.png?v=' + encodeURIComponent(key);
}

async function refresh() {
  try {
    const [jobs, workers] = await Promise.all([
      fetch('/api/v1/jobs').then(r => r.json()).then(x => x.jobs || []),
      fetch('/api/v1/workers').then(r => r.json()).then(x => x.workers || [])]);
    const body = document.querySelector('#jobs tbody');
    body.replaceChildren();
    const newest = jobs.slice().reverse();
    for (const j of newest) {
      const t = j.tasks || {};
      const name = el('span', '', j.id);
      if (j.spec && j.spec.label) name.appendChild(el('span', 'muted', ' · ' + j.spec.label));
      const tr = numeric(row([name, stateCell(j), j.integrator, progress(num(j.progress)), samplesCell(j),
        num(t.merged) + '/' + (num(t.total) > 0 ? num(t.total) : '?'),
        rate(j), acceptance(j).overall, clock(num(j.render_seconds))]), [4, 5, 6, 7, 8]);
      tr.className = 'job' + (pinned === j.id ? ' selected' : '');
      tr.dataset.job = j.id;
      tr.onclick = () => { pinned = j.id; refresh(); };
      body.appendChild(tr);
    }
    if (!jobs.length) body.appendChild(row([el('span', 'empty', 'no jobs yet')]));
    const withImage = newest.filter(j => num((j.tasks || {}).merged) > 0);
    const pick = withImage.find(j => j.id === pinned) || withImage.find(j => short(j.state) === 'running') || withImage[0];
    if (pick) showPreview(pick);

    const wbody = document.querySelector('#workers tbody');
    wbody.replaceChildren();
    const now = Date.now();
    for (const w of workers)
      wbody.appendChild(numeric(row([w.name || w.id, (w.peer || '').replace(/^ipv[46]:/, ''), badge(w.state),
        w.threads + '/' + w.cores, (w.attempt_ids || []).length, num(w.tasks_completed), num(w.tasks_failed),
        workerRate(w), ((now - num(w.last_seen_unix_ms)) / 1000).toFixed(0) + ' s ago', w.version]),
        [3, 4, 5, 6, 7, 8]));
    if (!workers.length) wbody.appendChild(row([el('span', 'empty', 'no workers registered')]));

    const alive = workers.filter(w => short(w.state) !== 'lost');
    const busy = alive.filter(w => short(w.state) === 'busy').length;
    const count = s => jobs.filter(j => short(j.state) === s).length;
    document.getElementById('summary').innerHTML = '';
    for (const [label, value] of [['workers', alive.length + ' (' + busy + ' busy)'],
        ['threads', alive.reduce((n, w) => n + num(w.threads), 0)], ['running', count('running')],
        ['queued', count('queued')], ['done', count('done')]]) {
      const s = el('span', '', label + ' ');
      s.appendChild(el('b', '', String(value)));
      document.getElementById('summary').appendChild(s);
    }
  } catch (e) { console.log(e); }
}
refresh();
setInterval(refresh, 1000);
</script></body></html>
)html";

}  // namespace

std::string_view dashboardPage() {
    static const std::string page = kHead + previewCss() + kBody;
    return page;
}

}  // namespace pf::master
