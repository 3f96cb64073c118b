// msdc live monitor: renders the JSON snapshot the server pushes once a second (server-sent events).
// Plain JS, no library; every text from the feed goes in through textContent (call signs are untrusted).
"use strict";
(() => {
  const PALETTE = ["#4fa3ff", "#ffb347", "#7fd17f", "#ff7eb6", "#c9a0ff", "#5ee0d6", "#f2e86d", "#ff8a65"];
  const STALE = "#5c6670";
  // no snapshot for this long (the server pushes one every 1-2.5 s): the connection is taken for lost, the
  // figures marked stale and the stream opened again (a half-open connection never reports an error)
  const SILENT_STREAM_MS = 10000;
  const RETRY_MS = 2000;  // a stream the browser gave up on is opened again this long after
  const $ = (id) => document.getElementById(id);
  const colours = new Map();
  let last = null;
  let snapshots = 0;
  let lastMessageMs = Date.now();  // when the latest message of the stream arrived (the browser's clock)
  let source = null;

  const colour = (sensorId) => {
    if (!colours.has(sensorId)) colours.set(sensorId, PALETTE[colours.size % PALETTE.length]);
    return colours.get(sensorId);
  };
  const el = (tag, text, attrs) => {
    const e = document.createElement(tag);
    if (text !== undefined && text !== null) e.textContent = text;
    for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
    return e;
  };
  const age = (s) => {
    if (s === null || s === undefined) return "–";
    if (s < 60) return `${s.toFixed(1)} s ago`;
    if (s < 3600) return `${Math.floor(s / 60)} min ${Math.floor(s % 60)} s ago`;
    return `${(s / 3600).toFixed(1)} h ago`;
  };
  const utc = (wallS) => new Date(wallS * 1000).toISOString().slice(11, 19) + " UTC";
  const num = (v, digits, unit) => (v === null || v === undefined ? "–" : `${v.toFixed(digits)}${unit || ""}`);
  const pct = (v) => `${(100 * v).toFixed(1)} %`;
  // a rate with the window it was measured over (shorter than the nominal window while uptime is)
  const rate = (v, digits, windowS) => (v === null || v === undefined ? "–"
    : `${v.toFixed(digits)} over ${Math.round(windowS)} s`);

  // one figure (probability of update, validity): its value and 95 % interval, or "–" with the reason
  const figure = (f) => {
    if (!f || f.value === null) return ["–", "withheld", f ? f.note : "no figure"];
    const text = `${pct(f.value)} [${pct(f.ci_low)}–${pct(f.ci_high)}] n=${f.n}`;
    if (f.state === "unjudged") return [text, "unjudged", `${f.count} of ${f.n}; ${f.note}`];
    const says = {ok: "at or above", low: "below (not yet shown by the sample)", degraded: "wholly below"};
    return [text, f.state, `${f.count} of ${f.n}; 95 % interval ${says[f.state]} the threshold ` +
            `${pct(f.threshold)}${f.note ? "; " + f.note : ""}`];
  };

  const renderAlarms = (alarms) => {
    const list = $("alarms");
    list.replaceChildren(...alarms.map((a) => el("li", a.message, {
      class: a.level, "data-kind": a.kind, "data-sensor": a.sensor_id || "", "data-feed": a.feed || ""})));
  };

  const renderSensors = (sensors) => {
    const box = $("sensors");
    box.replaceChildren(...sensors.map((s) => {
      const div = el("div", null, {class: "sensor" + (s.alarms.length ? " alarmed" : ""),
                                   "data-sensor-id": s.sensor_id});
      div.style.borderLeftColor = colour(s.sensor_id);
      div.append(el("h3", `${s.sensor_id}${s.kind ? " (" + s.kind + ")" : ""}`));
      const rows = [
        ["reports per second", rate(s.reports_per_s, 2, s.rate_window_s), "rate", "",
         `reports in the last ${Math.round(s.rate_window_s)} s (the window, or the time since the start)`],
        ["reports in window / records", `${s.reports_in_window} / ${s.records_total}`, "records", "", ""],
        ["figures measured on", s.figures_sample ? `${s.figures_sample.tracks} of ${s.figures_sample.of_tracks} tracks` : "every track", "sample", "", ""],
        ["update interval", num(s.update_interval_s, 2, " s"), "interval",
         s.update_interval_s === null ? "withheld" : "", s.update_interval_note],
        ["last report", age(s.last_report_age_s), "last-report",
         s.alarms.includes("silent") ? "degraded" : "", ""],
        ["last north marker / status", age(s.last_status_age_s), "last-status", "",
         s.last_status_age_s === null ? "no north marker or status message received from this sensor" : ""],
        ["probability of update", figure(s.pd)[0], "pd", ...figure(s.pd).slice(1)],
        ["Mode 3/A valid", figure(s.mode3a_valid)[0], "mode3a-valid", ...figure(s.mode3a_valid).slice(1)],
        ["Mode C valid", figure(s.modec_valid)[0], "modec-valid", ...figure(s.modec_valid).slice(1)],
        ["decode errors (its feeds)", String(s.decode_errors), "decode-errors", "", s.feeds.join(", ")],
      ];
      const table = el("table");
      for (const [name, value, key, state, note] of rows) {
        const tr = el("tr");
        tr.append(el("td", name), el("td", value, {class: state || "", "data-figure": key, title: note || ""}));
        table.append(tr);
      }
      div.append(table);
      return div;
    }));
  };

  const renderFeeds = (feeds) => {
    $("feeds").tBodies[0].replaceChildren(...feeds.map((f) => {
      const tr = el("tr", null, {"data-feed": f.feed});
      // every packet is one of these (docs/guide/live.md, Counters)
      const parts = `framed ${f.framed} + unframed ${f.unframed} + empty ${f.empty} + dropped ${f.dropped}` +
        ` + waiting to be decoded ${f.waiting}`;
      const over = `over the last ${Math.round(f.rate_window_s)} s`;
      tr.append(el("td", f.feed), el("td", rate(f.packets_per_s, 1, f.rate_window_s), {"data-counter": "rate"}),
                el("td", String(f.packets), {"data-counter": "packets", title: parts}),
                el("td", `${f.decode_errors} (+${f.decode_errors_in_window})`,
                        {title: `data blocks whose records do not decode, since start (+ ${over})`}),
                el("td", String(f.unframed), {"data-counter": "unframed"}),
                el("td", String(f.empty), {"data-counter": "empty", title: "datagrams of no byte"}),
                el("td", String(f.dropped), {"data-counter": "dropped"}),
                el("td", num(f.last_packet_age_s, 1, " s"), {title: "since the last packet"}));
      return tr;
    }));
  };

  const label = (t) => [t.callsign || (t.mode3a ? "A" + t.mode3a : t.track),
                        [t.mode3a && t.callsign ? "A" + t.mode3a : "",
                         t.flight_level === null ? "" : "FL" + Math.round(t.flight_level)].join(" ").trim()];

  const renderTargets = (targets) => {
    $("target-count").textContent = String(targets.length);
    $("targets").replaceChildren(...targets.map((t) => el("li",
      `${label(t).join(" ")} — ${t.sensor_id} ${t.track}, ${age(t.age_s)}${t.stale ? " (stale)" : ""}`,
      {"data-id": t.id, "data-sensor": t.sensor_id})));
  };

  const niceStep = (x) => {
    const p = Math.pow(10, Math.floor(Math.log10(x)));
    return [1, 2, 2.5, 5, 10].map((m) => m * p).find((s) => s >= x) || 10 * p;
  };

  // the map: nautical miles east and north of the targets' centroid (equirectangular), range rings around it
  const drawMap = (snap) => {
    const canvas = $("map");
    const dpr = window.devicePixelRatio || 1;
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
      canvas.width = Math.round(w * dpr);
      canvas.height = Math.round(h * dpr);
    }
    const g = canvas.getContext("2d");
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    const targets = snap.targets || [];
    const windowS = snap.thresholds ? snap.thresholds.window_s : 0;
    if (!snap.centre || !targets.length) {
      $("map-caption").textContent = `No target in the last ${windowS} s.`;
      document.body.dataset.targetsDrawn = "0";
      return;
    }
    const lat0 = snap.centre.latitude, lon0 = snap.centre.longitude;
    const k = Math.cos((lat0 * Math.PI) / 180);
    const nm = (p) => [((((p[1] - lon0) % 360) + 540) % 360 - 180) * 60 * k, (p[0] - lat0) * 60];
    // fitted to the targets' latest positions (a trail, or a stray position in it, may run off the map)
    let extent = 5;
    for (const t of targets) {
      const [x, y] = nm(t.trail[t.trail.length - 1]);
      extent = Math.max(extent, Math.abs(x), Math.abs(y));
    }
    extent *= 1.25;
    const scale = Math.min(w, h) / 2 / extent;
    const cx = w / 2, cy = h / 2;
    const px = (p) => { const [x, y] = nm(p); return [cx + x * scale, cy - y * scale]; };
    const step = niceStep(extent / 4);
    g.strokeStyle = "#24313d";
    g.fillStyle = "#5c6b7a";
    g.font = "11px system-ui, sans-serif";
    g.lineWidth = 1;
    for (let r = step; r * scale < Math.hypot(w, h) / 2; r += step) {
      g.beginPath();
      g.arc(cx, cy, r * scale, 0, 2 * Math.PI);
      g.stroke();
      g.fillText(`${r} NM`, cx + 3, cy - r * scale - 3);
    }
    g.beginPath(); g.moveTo(cx, 0); g.lineTo(cx, h); g.moveTo(0, cy); g.lineTo(w, cy); g.stroke();
    g.fillText("N", cx + 4, 12);
    let drawn = 0;
    for (const t of targets) {
      const c = t.stale ? STALE : colour(t.sensor_id);
      const pts = t.trail.map(px);
      g.strokeStyle = c;
      g.globalAlpha = 0.55;
      g.beginPath();
      pts.forEach(([x, y], i) => (i ? g.lineTo(x, y) : g.moveTo(x, y)));
      g.stroke();
      g.globalAlpha = 1;
      const [x, y] = pts[pts.length - 1];
      g.fillStyle = c;
      if (t.sensor_id.startsWith("021")) { g.beginPath(); g.arc(x, y, 3.5, 0, 2 * Math.PI); g.fill(); }
      else g.fillRect(x - 3.5, y - 3.5, 7, 7);
      const [top, bottom] = label(t);
      const adsb = t.sensor_id.startsWith("021");  // ADS-B labels left of the target, the others right
      g.textAlign = adsb ? "right" : "left";
      const lx = adsb ? x - 6 : x + 6;
      g.fillText(top, lx, y - 2);
      if (bottom) g.fillText(bottom, lx, y + 10);
      g.textAlign = "left";
      drawn += 1;
    }
    document.body.dataset.targetsDrawn = String(drawn);
    $("map-caption").textContent = `${drawn} targets of the last ${windowS} s around ` +
      `${lat0.toFixed(3)}°, ${lon0.toFixed(3)}°; rings every ${step} NM; grey: stale; ` +
      "squares: radar and others, dots: ADS-B (CAT021).";
  };

  const update = (snap) => {
    last = snap;
    snapshots += 1;
    document.body.dataset.snapshots = String(snapshots);
    const err = $("error");
    err.hidden = !snap.error;
    err.textContent = snap.error || "";
    if (!snap.thresholds) return;  // no snapshot computed yet: only the error to show
    // a failed snapshot brings the last good one again: its figures greyed, as of its time
    const failed = Boolean(snap.error);
    document.body.classList.toggle("stale", failed);
    if (failed) {
      err.textContent += `. The figures below are the last good snapshot's, as of ${utc(snap.now_wall_s)}.`;
    }
    $("clock").textContent = failed ? `last update ${utc(snap.now_wall_s)}` : utc(snap.now_wall_s);
    $("uptime").textContent = `up ${Math.round(snap.uptime_s)} s`;
    const th = snap.thresholds;
    $("thresholds").textContent = `Window ${th.window_s} s; alarms: silent after ${th.silent_s} s, ` +
      `probability of update < ${pct(th.min_pd)}, Mode 3/A valid < ${pct(th.min_mode3a_valid)}, ` +
      `Mode C valid < ${pct(th.min_modec_valid)} (95 % interval wholly below).`;
    renderAlarms(snap.alarms);
    renderSensors(snap.sensors);
    renderFeeds(snap.feeds);
    renderTargets(snap.targets);
    drawMap(snap);
  };

  // the connection lost: said, with the time of the last snapshot received, and its figures greyed
  const connectionLost = (why) => {
    document.body.classList.add("stale");
    $("connection").textContent = "connection lost, reconnecting…";
    $("connection").className = "down";
    const lost = $("lost");
    lost.hidden = false;
    if (last && last.now_wall_s) {
      const since = utc(last.now_wall_s);
      $("clock").textContent = `last update ${since}`;
      lost.textContent = `Connection to msdc lost (${why}): no snapshot since ${since}, the last one ` +
        `received. The figures below are stale, as of ${since}. Reconnecting…`;
    } else {
      lost.textContent = `Connection to msdc lost (${why}) before any snapshot arrived. Reconnecting…`;
    }
  };

  // a message arrived: the connection is live again, the figures current
  const connectionLive = () => {
    lastMessageMs = Date.now();
    document.body.classList.remove("stale");
    $("lost").hidden = true;
    $("connection").textContent = "live";
    $("connection").className = "up";
  };

  // the event stream; the browser reconnects by itself after a drop, and this page after the browser gives up
  const connect = () => {
    source = new EventSource("events");
    source.onerror = () => {
      connectionLost("the event stream dropped");
      if (source.readyState === EventSource.CLOSED) setTimeout(connect, RETRY_MS);
    };
    source.onmessage = (event) => {
      connectionLive();
      const snap = JSON.parse(event.data);
      if (!snap.pending) update(snap);
    };
  };

  // an open stream that brings nothing: lost all the same, and opened again
  const watchStream = () => {
    const silentMs = Date.now() - lastMessageMs;
    if (silentMs < SILENT_STREAM_MS) return;
    connectionLost(`no snapshot for ${Math.round(silentMs / 1000)} s`);
    if (source.readyState === EventSource.OPEN) {
      source.close();
      lastMessageMs = Date.now();  // the new stream gets its own SILENT_STREAM_MS
      connect();
    }
  };

  connect();
  setInterval(watchStream, 1000);
  window.addEventListener("resize", () => { if (last) drawMap(last); });
})();
