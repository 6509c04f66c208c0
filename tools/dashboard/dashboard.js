// floorpose dashboard: the plans from /api/plans, every wearer from the event stream
// /events (docs/dashboard.md). No framework and no network beyond the tool that serves it.
'use strict';

const MARGIN_PX = 24;    // the plan's bounds are fitted into the map with this margin
const TRAIL_MAX = 600;
const SVG = 'http://www.w3.org/2000/svg';

const plans = new Map();   // id -> {id, min, max, walls}
const devices = new Map(); // id -> {info, trail: [[x, y, flag]], age, stale}
const explored = new Map(); // plan id -> {info, image}: the team's explored map
let planId = null;         // the plan on screen
let choseByHand = false;
let drawQueued = false;

const $ = (sel) => document.querySelector(sel);

// Plan metres to pixels in #map: uniform scale, centred, y up.
function projection(plan) {
  const map = $('#map');
  const w = map.clientWidth, h = map.clientHeight;
  const spanX = Math.max(plan.max[0] - plan.min[0], 1e-3);
  const spanY = Math.max(plan.max[1] - plan.min[1], 1e-3);
  const s = Math.min((w - 2 * MARGIN_PX) / spanX, (h - 2 * MARGIN_PX) / spanY);
  const ox = (w - s * spanX) / 2, oy = (h - s * spanY) / 2;
  return {w, h, s, px: (x) => ox + s * (x - plan.min[0]), py: (y) => oy + s * (plan.max[1] - y)};
}

const LINE_STYLES = {
  window: {color: '#56B4E9', width: 0.6, dash: []},
  glass: {color: '#56B4E9', width: 0.6, dash: []},
  stairs: {color: '#E69F00', width: 1, dash: []},
  elevator: {color: '#CC79A7', width: 1, dash: []},
  door: {color: '#009E73', width: 0.8, dash: [1.5, 1.5]},
  exit: {color: '#D55E00', width: 1.4, dash: [1.5, 1]},
};

function drawPlan() {
  const canvas = $('#plan');
  const plan = plans.get(planId);
  const dpr = window.devicePixelRatio || 1;
  const map = $('#map');
  canvas.width = map.clientWidth * dpr;
  canvas.height = map.clientHeight * dpr;
  const ctx = canvas.getContext('2d');
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.clearRect(0, 0, map.clientWidth, map.clientHeight);
  if (!plan) return;
  const p = projection(plan);
  // Under the walls, the team's explored map (one pixel a cell) and its visited rooms.
  const team = explored.get(planId);
  if (team && team.image && team.image.complete && team.image.naturalWidth) {
    const e = team.info, size = p.s * e.cell_m;
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(team.image, p.px(e.origin[0]), p.py(e.origin[1] + e.height * e.cell_m),
                  e.width * size, e.height * size);
  }
  ctx.strokeStyle = getComputedStyle(document.documentElement).getPropertyValue('--wall');
  ctx.lineWidth = Math.max(1.5, Math.min(4, p.s * 0.08));
  ctx.lineCap = 'round';
  ctx.beginPath();
  for (const [ax, ay, bx, by] of plan.walls) {
    ctx.moveTo(p.px(ax), p.py(ay));
    ctx.lineTo(p.px(bx), p.py(by));
  }
  ctx.stroke();
  // The other lines by kind, in the Okabe-Ito colours (told apart with any colour vision):
  // glass and windows thin and light, doors and exits dashed (an opening), stairs and
  // elevators solid.
  const width = ctx.lineWidth;
  for (const [kind, style] of Object.entries(LINE_STYLES)) {
    const lines = (plan.lines || {})[kind];
    if (!lines) continue;
    ctx.strokeStyle = style.color;
    ctx.lineWidth = width * style.width;
    ctx.setLineDash(style.dash.map((d) => d * width));
    ctx.beginPath();
    for (const [ax, ay, bx, by] of lines) {
      ctx.moveTo(p.px(ax), p.py(ay));
      ctx.lineTo(p.px(bx), p.py(by));
    }
    ctx.stroke();
  }
  ctx.setLineDash([]);
  if (team) {
    ctx.fillStyle = '#1946a0';
    ctx.font = '12px system-ui, sans-serif';
    ctx.textAlign = 'center';
    for (const [x, y] of team.info.visited) ctx.fillText('\u2713 visited', p.px(x), p.py(y));
  }
}

function element(parent, tag, cls) {
  const e = document.createElementNS(SVG, tag);
  if (cls) e.setAttribute('class', cls);
  parent.appendChild(e);
  return e;
}

function deviceClass(d) {
  return d.stale ? 'stale' : d.info.pose ? d.info.pose.flag : 'lost';
}

function tooltip(d) {
  const pose = d.info.pose;
  const why = pose ? `${pose.flag} (p=${pose.probability}): ${pose.reason || 'ok'}` : 'no pose yet';
  return `${d.info.name}: ${why}` + (d.stale ? `; no data for ${d.age.toFixed(0)} s` : '');
}

function drawWearers() {
  const plan = plans.get(planId);
  const trails = $('#trails'), marks = $('#marks');
  trails.replaceChildren();
  marks.replaceChildren();
  if (!plan) return;
  const p = projection(plan);
  for (const [id, d] of devices) {
    if (d.info.plan !== planId || !d.info.pose) continue;
    const cls = deviceClass(d);
    const line = element(trails, 'polyline', 'trail ' + cls);
    line.setAttribute('data-device', id);
    line.setAttribute('points', d.trail.map(([x, y]) => `${p.px(x).toFixed(1)},${p.py(y).toFixed(1)}`).join(' '));
    const g = element(marks, 'g', 'wearer ' + cls);
    g.setAttribute('data-device', id);
    const x = p.px(d.info.pose.x), y = p.py(d.info.pose.y);
    g.setAttribute('transform', `translate(${x.toFixed(2)},${y.toFixed(2)})`);
    element(g, 'title').textContent = tooltip(d);
    // Heading: counter-clockwise from plan +x; the screen's y points down.
    const arrow = element(g, 'path', 'arrow');
    arrow.setAttribute('d', 'M 20 0 L 9 -6 L 9 6 Z');
    arrow.setAttribute('transform', `rotate(${(-d.info.pose.heading * 180 / Math.PI).toFixed(1)})`);
    const dot = element(g, 'circle', 'dot');
    dot.setAttribute('r', 8);
    const label = element(g, 'text');
    const leftOfDot = x > p.w - 120;  // near the right edge the name goes on the left
    label.setAttribute('x', leftOfDot ? -12 : 12);
    label.setAttribute('y', -12);
    if (leftOfDot) label.setAttribute('text-anchor', 'end');
    label.textContent = d.info.name;
  }
}

function ago(s) {
  return s < 60 ? `${s.toFixed(0)} s ago` : `${Math.floor(s / 60)} min ago`;
}

function drawList() {
  const body = $('#devices tbody');
  body.replaceChildren();
  for (const [id, d] of devices) {
    const tr = document.createElement('tr');
    tr.dataset.device = id;
    if (d.stale) tr.classList.add('stale');
    const pose = d.info.pose;
    const where = d.info.plan && d.info.plan !== planId ? ` (plan ${d.info.plan})` : '';
    const cells = [
      '', d.info.name + where, (d.info.state || '').toLowerCase().replace(/_/g, ' '),
      pose ? `${pose.flag} ${Math.round(pose.probability * 100)}%` : 'no pose', ago(d.age)];
    for (const text of cells) {
      const td = document.createElement('td');
      td.textContent = text;
      tr.appendChild(td);
    }
    const swatch = document.createElement('span');
    swatch.className = 'swatch ' + deviceClass(d);
    tr.firstChild.appendChild(swatch);
    tr.title = tooltip(d);
    body.appendChild(tr);
  }
}

function draw() {
  drawQueued = false;
  drawWearers();
  drawList();
}

function queueDraw() {
  if (!drawQueued) {
    drawQueued = true;
    requestAnimationFrame(draw);
  }
}

// Shows the plan most wearers are on, unless someone picked one.
function choosePlan() {
  if (choseByHand) return;
  const count = new Map();
  for (const d of devices.values())
    if (plans.has(d.info.plan)) count.set(d.info.plan, (count.get(d.info.plan) || 0) + 1);
  let best = planId && plans.has(planId) ? planId : plans.keys().next().value;
  for (const [id, n] of count) if (n > (count.get(best) || 0)) best = id;
  if (best !== planId) selectPlan(best);
}

function selectPlan(id) {
  planId = id;
  $('#plan-select').value = id;
  drawPlan();
  queueDraw();
}

function apply(frame) {
  for (const info of frame.devices) {
    const d = devices.get(info.id) || {trail: [], age: 0, stale: false};
    if (info.trail) {
      if (info.trail.reset) d.trail = [];
      d.trail.push(...info.trail.points);
      if (d.trail.length > TRAIL_MAX) d.trail.splice(0, d.trail.length - TRAIL_MAX);
    }
    delete info.trail;
    d.info = info;
    devices.set(info.id, d);
  }
  for (const [id, info] of Object.entries(frame.explored || {})) {
    const image = new Image();
    image.onload = () => {
      explored.set(id, {info, image});
      if (id === planId) drawPlan();
    };
    image.src = `/api/explored/${encodeURIComponent(id)}.png?v=${info.version}`;
    if (!explored.has(id)) explored.set(id, {info, image: null});
  }
  const stale = new Set(frame.stale);
  for (const [id, d] of devices) {
    d.age = frame.ages[id] ?? d.age;
    d.stale = stale.has(id);
  }
  choosePlan();
  queueDraw();
}

function connect() {
  const status = $('#connection');
  const events = new EventSource('/events');
  events.onopen = () => {
    status.textContent = 'live';
    status.className = 'open';
    devices.clear();  // the first frame of a stream is the whole picture
  };
  events.onmessage = (e) => apply(JSON.parse(e.data));
  events.onerror = () => {
    status.textContent = 'reconnecting';
    status.className = 'closed';
  };
}

async function start() {
  const response = await fetch('/api/plans');
  const body = await response.json();
  const select = $('#plan-select');
  for (const plan of body.plans) {
    plans.set(plan.id, plan);
    const option = document.createElement('option');
    option.value = option.textContent = plan.id;
    select.appendChild(option);
  }
  $('#plan-choice').hidden = body.plans.length < 2;
  select.onchange = () => {
    choseByHand = true;
    selectPlan(select.value);
  };
  if (body.plans.length) selectPlan(body.plans[0].id);
  new ResizeObserver(() => {
    drawPlan();
    queueDraw();
  }).observe($('#map'));
  connect();
}

start();
