/* sysid report charts: zoomable SVG line/marker plots, no dependencies, no network.
   Each <div class="sysid-chart" data-spec="ID"> is drawn from the JSON in
   <script type="application/json" id="ID">: {title, x: {label, log}, y: {label, log},
   equal, series: [{name, x, y, color, dash, mode: "line"|"markers", marker, size}],
   bands: [{name, x, lo, hi, color}]}.  Drag a box to zoom, double-click to reset;
   hovering shows the nearest point. */
(function () {
  "use strict";
  var NS = "http://www.w3.org/2000/svg";
  var W = 760, H = 300, M = {l: 64, r: 12, t: 26, b: 42};

  function el(tag, attrs, parent, text) {
    var e = document.createElementNS(NS, tag);
    for (var k in attrs) { e.setAttribute(k, attrs[k]); }
    if (text !== undefined) { e.textContent = text; }
    if (parent) { parent.appendChild(e); }
    return e;
  }
  function fmt(v) {
    if (v === 0) { return "0"; }
    var a = Math.abs(v);
    if (a >= 1e5 || a < 1e-3) { return v.toExponential(2); }
    return String(Number(v.toPrecision(4)));
  }
  function niceTicks(lo, hi, n) {
    var span = hi - lo, step = Math.pow(10, Math.floor(Math.log10(span / n)));
    var err = span / n / step;
    if (err >= 7.5) { step *= 10; } else if (err >= 3.5) { step *= 5; } else if (err >= 1.5) { step *= 2; }
    var out = [], t = Math.ceil(lo / step) * step;
    for (; t <= hi + step * 1e-9; t += step) { out.push(Math.abs(t) < step * 1e-9 ? 0 : t); }
    return out;
  }
  function logTicks(lo, hi) {  // lo, hi in log10 units
    var out = [];
    for (var d = Math.floor(lo); d <= Math.ceil(hi); d++) {
      if (d >= lo - 1e-9 && d <= hi + 1e-9) { out.push(d); }
    }
    if (out.length < 2) { return niceTicks(lo, hi, 4); }
    return out;
  }
  function tx(v, log) {
    if (v === null || v === undefined) { return NaN; }
    return log ? (v > 0 ? Math.log10(v) : NaN) : v;
  }
  function extent(spec) {
    var xl = spec.x.log, yl = spec.y.log, b = [Infinity, -Infinity, Infinity, -Infinity];
    function take(xs, ys) {
      for (var i = 0; i < xs.length; i++) {
        var a = tx(xs[i], xl), c = tx(ys[i], yl);
        if (isFinite(a) && isFinite(c)) {
          if (a < b[0]) { b[0] = a; } if (a > b[1]) { b[1] = a; }
          if (c < b[2]) { b[2] = c; } if (c > b[3]) { b[3] = c; }
        }
      }
    }
    (spec.series || []).forEach(function (s) { take(s.x, s.y); });
    (spec.bands || []).forEach(function (s) { take(s.x, s.lo); take(s.x, s.hi); });
    if (!isFinite(b[0])) { b = [0, 1, 0, 1]; }
    if (b[1] <= b[0]) { b[0] -= 0.5; b[1] += 0.5; }
    if (b[3] <= b[2]) { b[2] -= 0.5; b[3] += 0.5; }
    var pad = 0.04 * (b[3] - b[2]);
    b[2] -= pad; b[3] += pad;
    if (spec.equal) {  // same scale on both axes (pole-zero maps)
      var pw = W - M.l - M.r, ph = H - M.t - M.b;
      var sx = (b[1] - b[0]) / pw, sy = (b[3] - b[2]) / ph, s = Math.max(sx, sy);
      var cx = (b[0] + b[1]) / 2, cy = (b[2] + b[3]) / 2;
      b = [cx - s * pw / 2, cx + s * pw / 2, cy - s * ph / 2, cy + s * ph / 2];
    }
    return b;
  }

  function Chart(div, spec) {
    this.div = div; this.spec = spec; this.home = extent(spec); this.view = this.home.slice();
    this.svg = el("svg", {viewBox: "0 0 " + W + " " + H, width: "100%", role: "img",
                          "class": "sysid-svg"}, div);
    el("title", {}, this.svg, spec.title || "");
    var self = this;
    this.svg.addEventListener("mousedown", function (e) { self.down(e); });
    this.svg.addEventListener("mousemove", function (e) { self.move(e); });
    this.svg.addEventListener("mouseup", function (e) { self.up(e); });
    this.svg.addEventListener("mouseleave", function () { self.drag = null; self.hideTip(); });
    this.svg.addEventListener("dblclick", function () { self.view = self.home.slice(); self.draw(); });
    this.draw();
  }
  Chart.prototype.px = function (v) {
    var b = this.view;
    return M.l + (v - b[0]) / (b[1] - b[0]) * (W - M.l - M.r);
  };
  Chart.prototype.py = function (v) {
    var b = this.view;
    return H - M.b - (v - b[2]) / (b[3] - b[2]) * (H - M.t - M.b);
  };
  Chart.prototype.local = function (e) {
    var r = this.svg.getBoundingClientRect();
    return [(e.clientX - r.left) * W / r.width, (e.clientY - r.top) * H / r.height];
  };
  Chart.prototype.draw = function () {
    var s = this.spec, svg = this.svg, self = this, b = this.view;
    while (svg.childNodes.length > 1) { svg.removeChild(svg.lastChild); }
    var id = "clip-" + this.div.getAttribute("data-spec");
    var defs = el("defs", {}, svg), cp = el("clipPath", {id: id}, defs);
    el("rect", {x: M.l, y: M.t, width: W - M.l - M.r, height: H - M.t - M.b}, cp);
    el("text", {x: M.l, y: 16, "class": "t"}, svg, s.title || "");
    var xt = s.x.log ? logTicks(b[0], b[1]) : niceTicks(b[0], b[1], 8);
    var yt = s.y.log ? logTicks(b[2], b[3]) : niceTicks(b[2], b[3], 5);
    xt.forEach(function (t) {
      var x = self.px(t);
      el("line", {x1: x, x2: x, y1: M.t, y2: H - M.b, "class": "g"}, svg);
      el("text", {x: x, y: H - M.b + 14, "text-anchor": "middle", "class": "k"}, svg,
         fmt(s.x.log ? Math.pow(10, t) : t));
    });
    yt.forEach(function (t) {
      var y = self.py(t);
      el("line", {x1: M.l, x2: W - M.r, y1: y, y2: y, "class": "g"}, svg);
      el("text", {x: M.l - 4, y: y + 3, "text-anchor": "end", "class": "k"}, svg,
         fmt(s.y.log ? Math.pow(10, t) : t));
    });
    el("rect", {x: M.l, y: M.t, width: W - M.l - M.r, height: H - M.t - M.b, "class": "f"}, svg);
    el("text", {x: (M.l + W - M.r) / 2, y: H - 6, "text-anchor": "middle", "class": "a"}, svg,
       s.x.label || "");
    el("text", {x: 12, y: (M.t + H - M.b) / 2, "text-anchor": "middle", "class": "a",
                transform: "rotate(-90 12 " + (M.t + H - M.b) / 2 + ")"}, svg, s.y.label || "");
    var g = el("g", {"clip-path": "url(#" + id + ")"}, svg), drawn = 0;
    (s.bands || []).forEach(function (bd) {
      var up = [], dn = [];
      for (var i = 0; i < bd.x.length; i++) {
        var x = tx(bd.x[i], s.x.log), lo = tx(bd.lo[i], s.y.log), hi = tx(bd.hi[i], s.y.log);
        if (isFinite(x) && isFinite(lo) && isFinite(hi)) {
          up.push(self.px(x).toFixed(1) + "," + self.py(hi).toFixed(1));
          dn.unshift(self.px(x).toFixed(1) + "," + self.py(lo).toFixed(1));
        }
      }
      if (up.length) {
        el("polygon", {points: up.concat(dn).join(" "), fill: bd.color || "#1f77b4",
                       "fill-opacity": 0.18, stroke: "none", "class": "band"}, g);
        drawn++;
      }
    });
    (s.series || []).forEach(function (sr) {
      var pts = [];
      for (var i = 0; i < sr.x.length; i++) {
        var x = tx(sr.x[i], s.x.log), y = tx(sr.y[i], s.y.log);
        if (isFinite(x) && isFinite(y)) { pts.push([self.px(x), self.py(y)]); }
        else if (sr.mode !== "markers") { pts.push(null); }
      }
      var color = sr.color || "#1f77b4";
      if (sr.mode === "markers") {
        pts.forEach(function (p) {
          var r = sr.size || 3.5;
          if (sr.marker === "x") {
            el("path", {d: "M" + (p[0] - r) + "," + (p[1] - r) + "l" + 2 * r + "," + 2 * r +
                        "M" + (p[0] - r) + "," + (p[1] + r) + "l" + 2 * r + "," + -2 * r,
                        stroke: color, "stroke-width": 1.5, "class": "mk"}, g);
          } else {
            el("circle", {cx: p[0], cy: p[1], r: r, stroke: color,
                          fill: sr.marker === "open" ? "white" : color, "class": "mk"}, g);
          }
        });
        drawn += pts.length ? 1 : 0;
      } else {
        var d = "", pen = false;
        pts.forEach(function (p) {
          if (p === null) { pen = false; return; }
          d += (pen ? "L" : "M") + p[0].toFixed(1) + "," + p[1].toFixed(1);
          pen = true;
        });
        if (d) {
          el("path", {d: d, fill: "none", stroke: color, "stroke-width": sr.width || 1.3,
                      "stroke-dasharray": sr.dash || "none", "class": "ln"}, g);
          drawn++;
        }
      }
    });
    var named = (s.series || []).concat(s.bands || []).filter(function (x) { return x.name; });
    var lx = W - M.r - 6;
    named.slice().reverse().forEach(function (sr, k) {
      var y = M.t + 12 + 13 * (named.length - 1 - k);
      var t = el("text", {x: lx, y: y, "text-anchor": "end", "class": "lg"}, svg, sr.name);
      el("rect", {x: lx + 1, y: y - 7, width: 5, height: 7,
                  fill: sr.color || "#1f77b4"}, svg);
      return t;
    });
    this.box = el("rect", {"class": "zoom", visibility: "hidden"}, svg);
    this.tip = el("text", {x: M.l + 4, y: H - M.b - 6, "class": "tip"}, svg, "");
    this.div.setAttribute("data-rendered", String(drawn));
    this.div.setAttribute("data-view", b.map(fmt).join(","));
  };
  Chart.prototype.down = function (e) {
    var p = this.local(e);
    if (p[0] < M.l || p[0] > W - M.r || p[1] < M.t || p[1] > H - M.b) { return; }
    this.drag = p; e.preventDefault();
  };
  Chart.prototype.move = function (e) {
    var p = this.local(e);
    if (this.drag) {
      var x = Math.min(p[0], this.drag[0]), y = Math.min(p[1], this.drag[1]);
      this.box.setAttribute("x", x); this.box.setAttribute("y", y);
      this.box.setAttribute("width", Math.abs(p[0] - this.drag[0]));
      this.box.setAttribute("height", Math.abs(p[1] - this.drag[1]));
      this.box.setAttribute("visibility", "visible");
      return;
    }
    this.hover(p);
  };
  Chart.prototype.up = function (e) {
    if (!this.drag) { return; }
    var p = this.local(e), a = this.drag, b = this.view;
    this.drag = null; this.box.setAttribute("visibility", "hidden");
    if (Math.abs(p[0] - a[0]) < 5) { return; }
    var inv = function (px, lo, hi, p0, p1) { return lo + (px - p0) / (p1 - p0) * (hi - lo); };
    var x0 = inv(Math.min(p[0], a[0]), b[0], b[1], M.l, W - M.r);
    var x1 = inv(Math.max(p[0], a[0]), b[0], b[1], M.l, W - M.r);
    var y0 = b[2], y1 = b[3];
    if (Math.abs(p[1] - a[1]) >= 5) {
      y0 = inv(Math.max(p[1], a[1]), b[2], b[3], H - M.b, M.t);
      y1 = inv(Math.min(p[1], a[1]), b[2], b[3], H - M.b, M.t);
    }
    this.view = [x0, x1, y0, y1]; this.draw();
  };
  Chart.prototype.hideTip = function () { if (this.tip) { this.tip.textContent = ""; } };
  Chart.prototype.hover = function (p) {
    var s = this.spec, best = null, bd = 400, self = this;
    (s.series || []).forEach(function (sr) {
      for (var i = 0; i < sr.x.length; i++) {
        var x = tx(sr.x[i], s.x.log), y = tx(sr.y[i], s.y.log);
        if (!isFinite(x) || !isFinite(y)) { continue; }
        var dx = self.px(x) - p[0], dy = self.py(y) - p[1], d = dx * dx + dy * dy;
        if (d < bd) { bd = d; best = [sr.name || "", sr.x[i], sr.y[i]]; }
      }
    });
    this.tip.textContent = best ? best[0] + "  (" + fmt(best[1]) + ", " + fmt(best[2]) + ")" : "";
  };

  function drawAll() {
    var divs = document.querySelectorAll("div.sysid-chart");
    for (var i = 0; i < divs.length; i++) {
      var id = divs[i].getAttribute("data-spec");
      try {
        new Chart(divs[i], JSON.parse(document.getElementById(id).textContent));
      } catch (err) {
        divs[i].setAttribute("data-rendered", "error");
        console.error("sysid chart " + id + ": " + err);
      }
    }
    document.body.setAttribute("data-charts", "done");
  }
  if (document.readyState === "loading") {
    document.addEventListener("DOMContentLoaded", drawAll);
  } else { drawAll(); }
})();
