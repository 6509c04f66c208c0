// floorpose dashboard: the plans from /api/plans, every wearer from the event stream
// /events (docs/dashboard.md). No framework and no network beyond the tool that serves it.
'use strict';

const MARGIN_PX = 24;    // the plan's bounds are fitted into the map with this margin
const TRAIL_MAX = 600;
const SVG = 'http://www.w3.org/2000/svg';

const plans = new Map();   // id -> {id, min, max, walls, lines, set, floor}
const markers = new Map(); // id -> {id, kind, plan, floor, x, y, radius_m, text, author}
const searched = new Map(); // plan id -> Image of its rooms searched
let markersVersion = 0;
// The lead's zoom and pan over the fitted plan: screen = centre + zoom * (fitted - centre)
// + pan, per plan on screen; reset by "fit".
const view = {zoom: 1, panX: 0, panY: 0};
let placing = null;        // the marker kind to place with the next tap on the map
const routes = new Map();  // device id -> {to, path, message}: a way out drawn on request
const devices = new Map(); // id -> {info, trail: [[x, y, flag]], age, stale}
const explored = new Map(); // plan id -> {info, image}: the team's explored map
let planId = null;         // the plan on screen
let choseByHand = false;
let drawQueued = false;

const $ = (sel) => document.querySelector(sel);

// Plan metres to pixels in #map: uniform scale, centred, y up, then the lead's zoom and
// pan. x and y invert it (a tap's plan position).
function projection(plan) {
  const map = $('#map');
  const w = map.clientWidth, h = map.clientHeight;
  const spanX = Math.max(plan.max[0] - plan.min[0], 1e-3);
  const spanY = Math.max(plan.max[1] - plan.min[1], 1e-3);
  const fit = Math.min((w - 2 * MARGIN_PX) / spanX, (h - 2 * MARGIN_PX) / spanY);
  const s = fit * view.zoom;
  const ox = w / 2 + view.zoom * ((w - fit * spanX) / 2 - w / 2) + view.panX;
  const oy = h / 2 + view.zoom * ((h - fit * spanY) / 2 - h / 2) + view.panY;
  return {w, h, s, px: (x) => ox + s * (x - plan.min[0]), py: (y) => oy + s * (plan.max[1] - y),
          x: (px) => plan.min[0] + (px - ox) / s, y: (py) => plan.max[1] - (py - oy) / s};
}

// Zooms by `factor` about the screen point (cx, cy), which stays where it is.
function zoomAbout(factor, cx, cy) {
  const zoom = Math.min(64, Math.max(0.25, view.zoom * factor));
  const f = zoom / view.zoom;
  const map = $('#map');
  const w = map.clientWidth, h = map.clientHeight;
  // A point at screen q moves to c + f (q - c): the pan takes the part the zoom about the
  // map's centre does not.
  view.panX = (cx - w / 2) * (1 - f) + f * view.panX;
  view.panY = (cy - h / 2) * (1 - f) + f * view.panY;
  view.zoom = zoom;
  redraw();
}

function redraw() {
  drawPlan();
  queueDraw();
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
  // The rooms marked searched, green, on the plan's room grid.
  const done = searched.get(planId);
  if (done && done.complete && done.naturalWidth && plan.rooms_grid) {
    const g = plan.rooms_grid, size = p.s * g.cell_m;
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(done, p.px(g.origin[0]), p.py(g.origin[1] + g.height * g.cell_m),
                  g.width * size, g.height * size);
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
  drawScale(p);
  // North, when the plan is georeferenced: the screen's up is the plan's +y.
  const north = $('#north');
  north.hidden = plan.north_rad === undefined;
  if (!north.hidden)
    north.querySelector('path').setAttribute('transform', `rotate(${(90 - plan.north_rad * 180 / Math.PI).toFixed(1)})`);
  if (team) {
    ctx.fillStyle = '#1946a0';
    ctx.font = '12px system-ui, sans-serif';
    ctx.textAlign = 'center';
    for (const [x, y] of team.info.visited) ctx.fillText('\u2713 visited', p.px(x), p.py(y));
  }
}

// A scale bar of a round length (1, 2 or 5 times a power of ten metres) near 120 px.
function drawScale(p) {
  const target = 120 / p.s;
  const power = Math.pow(10, Math.floor(Math.log10(target)));
  const metres = [1, 2, 5, 10].map((k) => k * power).filter((m) => m <= target).pop() || power;
  $('#scale-bar').style.width = `${(metres * p.s).toFixed(1)}px`;
  $('#scale-label').textContent = metres >= 1 ? `${metres} m` : `${Math.round(metres * 100)} cm`;
  $('#scale').dataset.metres = metres;
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

function drawMarkers(plan, p) {
  const layer = $('#markers');
  layer.replaceChildren();
  for (const [id, m] of markers) {
    if (m.removed || m.plan !== plan.id) continue;
    const g = element(layer, 'g', 'marker ' + m.kind);
    g.dataset.id = id;
    g.setAttribute('transform', `translate(${p.px(m.x).toFixed(2)},${p.py(m.y).toFixed(2)})`);
    if (m.kind === 'hazard' || m.kind === 'blocked') {
      const area = element(g, 'circle', 'area');
      area.setAttribute('r', (p.s * (m.radius_m || 1)).toFixed(1));
    }
    element(g, 'circle', 'pin').setAttribute('r', 10);
    const label = element(g, 'text');
    label.setAttribute('x', 13);
    label.setAttribute('y', 4);
    label.textContent = m.kind + (m.text ? `: ${m.text}` : '') + (m.author ? ` (${m.author})` : '');
    element(g, 'title').textContent = label.textContent;
    g.addEventListener('click', (e) => {
      e.stopPropagation();
      if (confirm(`Remove this marker? ${label.textContent}`)) post('/api/markers', {id, removed: true});
    });
  }
}

function drawWearers() {
  const plan = plans.get(planId);
  const trails = $('#trails'), marks = $('#marks');
  trails.replaceChildren();
  marks.replaceChildren();
  if (!plan) return;
  const p = projection(plan);
  drawMarkers(plan, p);
  for (const [id, d] of devices) {
    if (d.info.plan !== planId || !d.info.pose) continue;
    const cls = deviceClass(d);
    const line = element(trails, 'polyline', 'trail ' + cls);
    line.setAttribute('data-device', id);
    line.setAttribute('points', d.trail.map(([x, y]) => `${p.px(x).toFixed(1)},${p.py(y).toFixed(1)}`).join(' '));
    const route = routes.get(id);
    if (route && route.path.length) {
      const way = element(trails, 'polyline', 'route ' + route.to);
      way.setAttribute('data-device', id);
      way.setAttribute('points', route.path.map(([x, y]) => `${p.px(x).toFixed(1)},${p.py(y).toFixed(1)}`).join(' '));
    }
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

// Where a plan is in the selector: its set and floor, or its id.
function planLabel(id) {
  const plan = plans.get(id);
  return plan && plan.set ? `${plan.set} floor ${plan.floor}` : id;
}

function alertText(d) {
  const a = d.info.alert;
  if (!a) return '';
  const what = a.kind === 'no_motion' ? 'NO MOTION' : 'not moving';
  return `${what} for ${a.still_s.toFixed(0)} s` + (a.acknowledged ? ` (acknowledged by ${a.by})` : '');
}

// What the list and the banner show, as a string: they are rebuilt only when it changes,
// so that a button is not replaced under a finger mid-tap.
let listShown = '', alertsShown = '';

function drawList() {
  const body = $('#devices tbody');
  const signature = JSON.stringify([planId, [...devices].map(([id, d]) => [id, d.info, Math.round(d.age), d.stale]),
                                    [...routes]]);
  if (signature === listShown) return;
  listShown = signature;
  body.replaceChildren();
  for (const [id, d] of devices) {
    const tr = document.createElement('tr');
    tr.dataset.device = id;
    if (d.stale) tr.classList.add('stale');
    const alert = d.info.alert;
    if (alert && alert.kind === 'no_motion') tr.classList.add('alert');
    if (alert && alert.acknowledged) tr.classList.add('acknowledged');
    const pose = d.info.pose;
    const where = d.info.plan && d.info.plan !== planId ? ` (${planLabel(d.info.plan)})` : '';
    const cells = [
      '', d.info.name + where, (d.info.state || '').toLowerCase().replace(/_/g, ' '),
      // A wearer whose data stopped has no reliability now: its last one is in the reason.
      d.stale ? 'unknown' : pose ? `${pose.flag} ${Math.round(pose.probability * 100)}%` : 'no pose',
      d.stale ? `no data for ${d.age.toFixed(0)} s` : ago(d.age)];
    for (const text of cells) {
      const td = document.createElement('td');
      td.textContent = text;
      tr.appendChild(td);
    }
    const swatch = document.createElement('span');
    swatch.className = 'swatch ' + deviceClass(d);
    tr.firstChild.appendChild(swatch);
    body.appendChild(tr);
    // The wearer's way out and way back, asked of its daemon, drawn on the map.
    const ways = document.createElement('tr');
    ways.dataset.waysOf = id;
    const cell = document.createElement('td');
    cell.colSpan = 5;
    for (const [to, label] of [['exit', 'way out'], ['backtrack', 'way back']]) {
      const button = document.createElement('button');
      button.textContent = label;
      button.dataset.to = to;
      const shown = routes.get(id);
      if (shown && shown.to === to) button.classList.add('active');
      button.onclick = () => showRoute(id, to);
      cell.appendChild(button);
    }
    const said = routes.get(id);
    if (said && said.message) cell.append(' ' + said.message);
    ways.appendChild(cell);
    body.appendChild(ways);
    // Every state and reason in sight, not on hover: a tablet has no hover.
    const why = document.createElement('tr');
    why.dataset.reasonOf = id;
    const td = document.createElement('td');
    td.colSpan = 5;
    td.className = 'why';
    td.textContent = [alertText(d), tooltip(d)].filter(Boolean).join(' \u2014 ');
    why.appendChild(td);
    body.appendChild(why);
  }
}

// The banner: every wearer in alert whom no lead has acknowledged, with a button; a tone
// while one is there.
let audio = null;
// Wearers whose data stopped, acknowledged on this page (the daemon may be gone, so the
// acknowledgement is the page's own); cleared when their data comes back.
const noDataSeen = new Set();

function drawAlerts() {
  const banner = $('#alerts');
  for (const [id, d] of devices) if (!d.stale) noDataSeen.delete(id);
  const signature = JSON.stringify([[...devices].map(([id, d]) => [id, d.info.alert, d.info.name,
                                                                  d.stale && Math.round(d.age)]),
                                    [...noDataSeen]]);
  tone(!banner.hidden);
  if (signature === alertsShown) return;
  alertsShown = signature;
  // Rows are kept and only their text changes: a banner rebuilt every second (a silent
  // wearer's age ticks) would swallow a lead's tap landing between press and release.
  const wanted = [];
  for (const [id, d] of devices) {
    const a = d.info.alert;
    if (a && a.kind === 'no_motion' && !a.acknowledged)
      wanted.push({id, kind: 'no-motion', text: `${d.info.name}: ${alertText(d)}`,
                   acknowledge: () => post('/api/alerts/ack', {device: id})});
    if (d.stale && !noDataSeen.has(id))
      wanted.push({id, kind: 'no-data', text: `${d.info.name}: NO DATA for ${d.age.toFixed(0)} s`,
                   acknowledge: () => {
                     noDataSeen.add(id);
                     queueDraw();
                   }});
  }
  const key = (id, kind) => id + '\n' + kind;
  const rows = new Map([...banner.children].map(r => [key(r.dataset.device, r.dataset.kind), r]));
  const keep = new Set(wanted.map(w => key(w.id, w.kind)));
  for (const [k, r] of rows)
    if (!keep.has(k)) r.remove();
  let before = banner.firstChild;
  for (const w of wanted) {
    let row = rows.get(key(w.id, w.kind));
    if (!row) {
      row = document.createElement('div');
      row.className = 'alert ' + w.kind;
      row.dataset.device = w.id;
      row.dataset.kind = w.kind;
      row.append(document.createElement('span'), document.createElement('button'));
      row.lastChild.textContent = 'Acknowledge';
    }
    if (row.firstChild.textContent !== w.text) row.firstChild.textContent = w.text;
    row.lastChild.onclick = w.acknowledge;
    if (row !== before) banner.insertBefore(row, before);
    else before = before.nextSibling;
  }
  banner.hidden = !banner.childElementCount;
  tone(!banner.hidden);
}

function tone(on) {
  try {
    if (!on) {
      if (audio) audio.osc.frequency.value = 0;
      return;
    }
    if (!audio) {
      const ctx = new AudioContext();
      const osc = ctx.createOscillator(), gain = ctx.createGain();
      gain.gain.value = 0.1;
      osc.connect(gain).connect(ctx.destination);
      osc.start();
      audio = {ctx, osc};
    }
    audio.osc.frequency.value = Math.floor(Date.now() / 500) % 2 ? 880 : 660;
  } catch (e) {
    // No audio output (a browser that blocks it until a tap): the banner still shows.
  }
}

async function showRoute(id, to) {
  const shown = routes.get(id);
  if (shown && shown.to === to) {
    routes.delete(id);  // a second press hides it
  } else {
    const response = await post('/api/route', {device: id, to});
    const reply = response.ok || response.status === 409 ? await response.json() : null;
    routes.set(id, {to, path: reply && reply.ok ? reply.path : [],
                    message: reply ? reply.message : 'no answer from the wearer\'s daemon'});
  }
  queueDraw();
}

async function post(path, body) {
  const response = await fetch(path, {method: 'POST', headers: {'Content-Type': 'application/json'},
                                      body: JSON.stringify(body)});
  if (!response.ok) console.warn(path, response.status);
  return response;
}

function draw() {
  drawQueued = false;
  drawWearers();
  drawList();
  drawAlerts();
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
  if (id !== planId) Object.assign(view, {zoom: 1, panX: 0, panY: 0});
  planId = id;
  $('#plan-select').value = id;
  redraw();
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
  if (frame.markers) {
    markers.clear();
    for (const m of frame.markers) markers.set(m.id, m);
    // The searched rooms of every plan with a searched marker, again.
    ++markersVersion;
    searched.clear();
    for (const id of new Set(frame.markers.filter((m) => m.kind === 'searched' && !m.removed)
                                       .map((m) => m.plan))) {
      const image = new Image();
      image.onload = () => { if (id === planId) drawPlan(); };
      image.src = `/api/searched/${encodeURIComponent(id)}.png?v=${markersVersion}`;
      searched.set(id, image);
    }
    drawPlan();
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
    markers.clear();
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
    option.value = plan.id;
    option.textContent = planLabel(plan.id);
    select.appendChild(option);
  }
  $('#plan-choice').hidden = body.plans.length < 2;
  select.onchange = () => {
    choseByHand = true;
    selectPlan(select.value);
  };
  if (body.plans.length) selectPlan(body.plans[0].id);
  new ResizeObserver(redraw).observe($('#map'));
  // Browsers keep audio suspended until the page is touched: the first tap lets the alert
  // tone sound.
  document.addEventListener('pointerdown', () => audio && audio.ctx.resume());
  listenToTheMap();
  connect();
}

// Wheel and pinch zoom, drag to pan, tap to place a marker.
function listenToTheMap() {
  const map = $('#map');
  const local = (e) => {
    const r = map.getBoundingClientRect();
    return [e.clientX - r.left, e.clientY - r.top];
  };
  map.addEventListener('wheel', (e) => {
    e.preventDefault();
    const [x, y] = local(e);
    zoomAbout(Math.exp(-e.deltaY * 0.002), x, y);
  }, {passive: false});
  const pointers = new Map();  // id -> [x, y]
  let moved = 0;
  map.addEventListener('pointerdown', (e) => {
    pointers.set(e.pointerId, local(e));
    moved = 0;
  });
  map.addEventListener('pointermove', (e) => {
    if (!pointers.has(e.pointerId)) return;
    const [x, y] = local(e);
    const [px, py] = pointers.get(e.pointerId);
    if (pointers.size === 1) {
      view.panX += x - px;
      view.panY += y - py;
      moved += Math.abs(x - px) + Math.abs(y - py);
      pointers.set(e.pointerId, [x, y]);
      redraw();
    } else if (pointers.size === 2) {
      const [other] = [...pointers].filter(([id]) => id !== e.pointerId).map(([, p]) => p);
      const before = Math.hypot(px - other[0], py - other[1]);
      const after = Math.hypot(x - other[0], y - other[1]);
      pointers.set(e.pointerId, [x, y]);
      moved += 100;
      if (before > 0) zoomAbout(after / before, (x + other[0]) / 2, (y + other[1]) / 2);
    }
  });
  const up = (e) => pointers.delete(e.pointerId);
  map.addEventListener('pointerup', up);
  map.addEventListener('pointercancel', up);
  map.addEventListener('click', (e) => {
    const plan = plans.get(planId);
    if (!placing || !plan || moved > 6) return;
    const [x, y] = local(e);
    const p = projection(plan);
    const text = placing === 'note' ? prompt('Note') || '' : '';
    post('/api/markers', {kind: placing, plan: plan.id, floor: plan.floor || '',
                          x: p.x(x), y: p.y(y), text});
    setPlacing(null);
  });
  $('#zoom-in').onclick = () => zoomAbout(1.5, map.clientWidth / 2, map.clientHeight / 2);
  $('#zoom-out').onclick = () => zoomAbout(1 / 1.5, map.clientWidth / 2, map.clientHeight / 2);
  $('#zoom-fit').onclick = () => {
    Object.assign(view, {zoom: 1, panX: 0, panY: 0});
    redraw();
  };
  for (const button of document.querySelectorAll('#marker-kinds button'))
    button.onclick = () => setPlacing(placing === button.dataset.kind ? null : button.dataset.kind);
}

function setPlacing(kind) {
  placing = kind;
  for (const button of document.querySelectorAll('#marker-kinds button'))
    button.classList.toggle('active', button.dataset.kind === kind);
}

start();
