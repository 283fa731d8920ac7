/* quickrelease: the zoomable record figures of the report (quickrelease/report/zoom.py writes their data).
   Each figure: per channel a panel of the record (points) and the fitted model (line), and a panel of the
   residuals with the +-2 sigma band; the release and the stick marked. Every panel of a figure shares the time
   axis (drag a box: zoom; Shift + drag: pan; Shift + wheel: zoom about the pointer; double click: the whole
   record) and the cursor. window.quickreleaseZoom[id] = {charts, setX(min, max), reset(), full} for tests. */
(function () {
  "use strict";
  var figures = (window.quickreleaseZoom = {});

  function floats(b64) {  // base64 of little-endian float32 -> Array, NaN -> null (a gap)
    var bin = atob(b64), n = bin.length >> 2, view = new DataView(new ArrayBuffer(bin.length)), out = new Array(n);
    for (var i = 0; i < bin.length; i++) view.setUint8(i, bin.charCodeAt(i));
    for (var k = 0; k < n; k++) {
      var v = view.getFloat32(4 * k, true);
      out[k] = isFinite(v) ? v : null;
    }
    return out;
  }

  function times(spec) {  // {t0, dt, runs: [[first step, samples], ...]} or {t0, offsets} -> Array [s]
    if (spec.offsets != null) return floats(spec.offsets).map(function (v) { return spec.t0 + v; });
    var out = [];
    spec.runs.forEach(function (run) {
      for (var j = 0; j < run[1]; j++) out.push(spec.t0 + (run[0] + j) * spec.dt);
    });
    return out;
  }

  function fmt(v) { return v == null ? "\u2013" : String(+v.toPrecision(5)); }

  function draw(root) {
    var spec = JSON.parse(document.getElementById(root.getAttribute("data-qr-zoom")).textContent);
    var colors = spec.colors, charts = [], current = {min: null, max: null};
    var full = {min: Infinity, max: -Infinity};
    var width = Math.max(root.clientWidth || 0, 320);

    function setX(min, max) {  // every panel to [min, max] (the shared time axis)
      current = {min: min, max: max};
      charts.forEach(function (u) {
        if (u.scales.x.min !== min || u.scales.x.max !== max) u.setScale("x", {min: min, max: max});
      });
    }

    function reset() { setX(full.min, full.max); }

    function follow(u, key) {  // a panel's time axis changed (its own zoom): the others follow
      if (key !== "x" || (u.scales.x.min === current.min && u.scales.x.max === current.max)) return;
      setX(u.scales.x.min, u.scales.x.max);
    }

    function markers(u) {  // the release and the stick, dashed vertical lines with their names
      var ctx = u.ctx, box = u.bbox, px = uPlot.pxRatio;
      ctx.save();
      ctx.beginPath();
      ctx.rect(box.left, box.top, box.width, box.height);
      ctx.clip();
      ctx.strokeStyle = colors.record;
      ctx.fillStyle = "#333";
      ctx.lineWidth = px;
      ctx.setLineDash([4 * px, 3 * px]);
      ctx.font = Math.round(11 * px) + "px system-ui, sans-serif";
      ctx.textAlign = "left";
      ctx.textBaseline = "alphabetic";
      spec.markers.forEach(function (m) {
        var x = Math.round(u.valToPos(m.t, "x", true));
        ctx.beginPath();
        ctx.moveTo(x, box.top);
        ctx.lineTo(x, box.top + box.height);
        ctx.stroke();
        if (u.showLabels) ctx.fillText(m.label, x + 3 * px, box.top + 12 * px);
      });
      ctx.restore();
    }

    function band(sigma) {  // the +-2 sigma band of the noise, under the residuals
      return function (u) {
        if (sigma == null) return;
        var ctx = u.ctx, box = u.bbox;
        var top = u.valToPos(2 * sigma, "y", true), bottom = u.valToPos(-2 * sigma, "y", true);
        ctx.save();
        ctx.beginPath();
        ctx.rect(box.left, box.top, box.width, box.height);
        ctx.clip();
        ctx.globalAlpha = 0.15;
        ctx.fillStyle = colors.band;
        ctx.fillRect(box.left, top, box.width, bottom - top);
        ctx.restore();
      };
    }

    function pan(u) {  // Shift + drag (or the middle button): the time axis follows the pointer
      return function (e) {
        if (!(e.shiftKey || e.button === 1)) return;
        e.preventDefault();
        e.stopPropagation();  // not a zoom box
        var x0 = e.clientX, min0 = u.scales.x.min, max0 = u.scales.x.max;
        var perPx = (max0 - min0) / u.over.clientWidth;
        function move(ev) { var dx = perPx * (ev.clientX - x0); setX(min0 - dx, max0 - dx); }
        function up() {
          document.removeEventListener("mousemove", move);
          document.removeEventListener("mouseup", up);
        }
        document.addEventListener("mousemove", move);
        document.addEventListener("mouseup", up);
      };
    }

    function wheel(u) {  // Shift + wheel: zoom the time axis about the pointer (a plain wheel scrolls the page)
      return function (e) {
        if (!e.shiftKey) return;
        var delta = e.deltaY || e.deltaX;  // Shift turns the wheel sideways in some browsers
        if (!delta) return;
        e.preventDefault();
        var rect = u.over.getBoundingClientRect(), min = u.scales.x.min, max = u.scales.x.max;
        var at = u.posToVal(e.clientX - rect.left, "x"), factor = delta < 0 ? 0.75 : 1 / 0.75;
        var lo = at - (at - min) * factor, hi = at + (max - at) * factor;
        setX(Math.max(lo, full.min), Math.min(hi, full.max));
      };
    }

    function panel(title, ylabel, data, series, hooks, height, last, yrange) {
      var opts = {
        title: title, width: width, height: height,
        scales: {x: {time: false, auto: false, range: function (u, min, max) { return [min, max]; }},
                 y: yrange ? {range: yrange} : {}},
        cursor: {sync: {key: root.id, setSeries: false,
                        filters: {pub: function (type) { return type === "mousemove" || type === "mouseleave"
                                                               || type === "mouseenter"; }}},
                 drag: {x: true, y: false, setScale: true},
                 bind: {dblclick: function () { return function (e) { if (e.button === 0) reset(); }; }}},
        legend: {live: true},
        axes: [{label: last ? spec.xlabel : null, labelSize: last ? 20 : 0, size: 36},
               {label: ylabel, size: 78, labelSize: 20, labelFont: "bold 11px system-ui, sans-serif", space: 20,
                values: function (u, vals) { return vals.map(fmt); }}],
        series: [{label: "t [s]", value: function (u, v) { return v == null ? "\u2013" : v.toFixed(3); }}]
          .concat(series),
        hooks: {setScale: [follow], draw: [markers], drawClear: hooks.drawClear || []},
      };
      var u = new uPlot(opts, data, root);
      u.showLabels = !!hooks.labels;
      u.over.parentNode.addEventListener("mousedown", pan(u), true);
      u.over.addEventListener("wheel", wheel(u), {passive: false});
      charts.push(u);
      return u;
    }

    var hint = document.createElement("p");
    hint.className = "qr-hint";
    hint.textContent = spec.hint;
    root.appendChild(hint);
    var decoded = spec.channels.map(function (c) {
      var t = times(c.t), tm = times(c.model_t);
      [t[0], t[t.length - 1], tm[0], tm[tm.length - 1]].forEach(function (v) {
        if (v != null && isFinite(v)) { full.min = Math.min(full.min, v); full.max = Math.max(full.max, v); }
      });
      return {c: c, t: t, tm: tm, values: floats(c.values), residual: floats(c.residual), model: floats(c.model)};
    });
    current = {min: full.min, max: full.max};
    decoded.forEach(function (d, k) {
      var c = d.c, unit = " [" + c.unit + "]";
      var joined = uPlot.join([[d.t, d.values], [d.tm, d.model]]);
      panel(c.name + ": record and " + spec.model_label, c.name + unit, joined, [
        {label: "record", stroke: colors.record, paths: function () { return null; }, value: function (u, v) {
          return fmt(v); }, points: {show: true, size: 3, width: 0, fill: colors.record, stroke: colors.record}},
        {label: spec.model_label, stroke: colors.model, width: 1.2, spanGaps: true, points: {show: false},
         value: function (u, v) { return fmt(v); }},
      ], {labels: true}, 220, false, null);
      var sigma = c.sigma;
      panel(null, "residual" + unit, [d.t, d.residual], [
        {label: "residual", stroke: colors.residual, paths: function () { return null; }, value: function (u, v) {
          return fmt(v); }, points: {show: true, size: 3, width: 0, fill: colors.residual, stroke: colors.residual}},
      ], {drawClear: [band(sigma)]}, 140, k === decoded.length - 1, function (u, min, max) {
        var s = sigma == null ? 0 : 2 * sigma;
        var lo = Math.min(min == null ? -s : min, -s), hi = Math.max(max == null ? s : max, s);
        var pad = 0.05 * ((hi - lo) || 1);
        return [lo - pad, hi + pad];
      });
    });
    setX(full.min, full.max);
    window.addEventListener("resize", function () {
      var w = Math.max(root.clientWidth || 0, 320);
      charts.forEach(function (u) { u.setSize({width: w, height: u.height}); });
    });
    root.parentNode.classList.add("qr-live");  // every panel drawn: the static figure steps aside (not in print)
    figures[root.parentNode.id] = {charts: charts, setX: setX, reset: reset, full: full};
  }

  var roots = document.querySelectorAll("[data-qr-zoom]");
  for (var i = 0; i < roots.length; i++) {
    try {
      draw(roots[i]);
    } catch (err) {  // the static figure stays in view
      roots[i].textContent = "";
      console.error("quickrelease: the zoomable figure could not be drawn:", err);
    }
  }
})();
