// Draws the figures embedded as JSON (element #mppi-figures) on canvases, one per panel, with
// the limits and ticks of the PNG copies, and shows the nearest data point under the pointer.
(function () {
  "use strict";
  var figures = JSON.parse(document.getElementById("mppi-figures").textContent);
  var tip = document.getElementById("mppi-tip");
  var FONT = '"DejaVu Sans", Verdana, sans-serif';

  function decimals(step) { return Math.max(0, -Math.floor(Math.log10(step) + 1e-9)); }
  function tickLabel(v, step) {
    var mag = Math.max(Math.abs(v), step);
    if (mag >= 1e6 || step < 1e-4) return v.toExponential(Math.min(12, Math.max(0, Math.ceil(Math.log10(mag / step) - 1e-9))));
    return (Math.abs(v) < 0.5 * step ? 0 : v).toFixed(decimals(step));
  }
  function ticks(axis) {
    var out = [], first = Math.ceil(axis.lo / axis.step - 1e-9), last = Math.floor(axis.hi / axis.step + 1e-9);
    for (var i = first; i <= last; i++) out.push(i * axis.step);
    return out;
  }
  function dash(ctx, d, w) { ctx.setLineDash(d === "dashed" ? [7, 4] : d === "dotted" ? [Math.max(1.5, w), 3] : []); }
  function valueFormat(v) { return Math.abs(v) >= 1e5 || (v !== 0 && Math.abs(v) < 1e-3) ? v.toExponential(4) : v.toPrecision(5); }

  function drawPanel(canvas, p, W, H) {
    var ratio = window.devicePixelRatio || 1;
    canvas.width = W * ratio; canvas.height = H * ratio;
    canvas.style.width = W + "px"; canvas.style.height = H + "px";
    var ctx = canvas.getContext("2d");
    ctx.scale(ratio, ratio);
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, W, H);
    var xa = p.x_axis, ya = p.y_axis;
    var yw = 0;
    ctx.font = "12px " + FONT;
    ticks(ya).forEach(function (t) { yw = Math.max(yw, ctx.measureText(tickLabel(t, ya.step)).width); });
    var left = 10 + (p.y_label ? 22 : 0) + yw + 8, right = 18 + (p.right_axis ? yw + 8 : 0) + (p.trail ? 110 : 0);
    var top = p.title ? 34 : 14, bottom = 8 + 12 + 8 + (p.x_label ? 18 : 0) + 8;
    var aw = W - left - right, ah = H - top - bottom;
    if (p.equal_scale) {  // same data units per pixel on both axes; limits grow around the centre
      var s = Math.max((xa.hi - xa.lo) / aw, (ya.hi - ya.lo) / ah), cx = (xa.lo + xa.hi) / 2, cy = (ya.lo + ya.hi) / 2;
      xa = {lo: cx - s * aw / 2, hi: cx + s * aw / 2, step: xa.step};
      ya = {lo: cy - s * ah / 2, hi: cy + s * ah / 2, step: ya.step};
    }
    function px(x) { return left + (x - xa.lo) / (xa.hi - xa.lo) * aw; }
    function py(y) { return top + ah - (y - ya.lo) / (ya.hi - ya.lo) * ah; }
    // Grid.
    ctx.strokeStyle = "#e1e1e1"; ctx.lineWidth = 1; ctx.setLineDash([]);
    ticks(xa).forEach(function (t) { ctx.beginPath(); ctx.moveTo(px(t), top); ctx.lineTo(px(t), top + ah); ctx.stroke(); });
    ticks(ya).forEach(function (t) { ctx.beginPath(); ctx.moveTo(left, py(t)); ctx.lineTo(left + aw, py(t)); ctx.stroke(); });
    ctx.save();
    ctx.beginPath(); ctx.rect(left, top, aw, ah); ctx.clip();
    var points = [];
    p.ref_lines.forEach(function (r) {
      ctx.strokeStyle = r.colour; ctx.lineWidth = r.width_px; dash(ctx, r.dash, r.width_px);
      ctx.beginPath();
      if (r.horizontal) { ctx.moveTo(left, py(r.at)); ctx.lineTo(left + aw, py(r.at)); }
      else { ctx.moveTo(px(r.at), top); ctx.lineTo(px(r.at), top + ah); }
      ctx.stroke();
    });
    function drawSeries(s) {
      ctx.strokeStyle = s.colour; ctx.fillStyle = s.colour;
      if (s.width_px > 0 && s.x.length > 1) {
        ctx.lineWidth = s.width_px; dash(ctx, s.dash, s.width_px);
        ctx.beginPath();
        for (var i = 0; i < s.x.length; i++) (i ? ctx.lineTo : ctx.moveTo).call(ctx, px(s.x[i]), py(s.y[i]));
        ctx.stroke();
      }
      ctx.setLineDash([]);
      var r = s.marker_px / 2;
      for (var k = 0; k < s.x.length; k++) {
        var X = px(s.x[k]), Y = py(s.y[k]);
        if (s.marker === "circle") { ctx.beginPath(); ctx.arc(X, Y, r, 0, 2 * Math.PI); ctx.fill(); }
        else if (s.marker === "square") ctx.fillRect(X - r, Y - r, 2 * r, 2 * r);
        else if (s.marker === "cross") {
          ctx.lineWidth = Math.max(2, 0.3 * s.marker_px); ctx.beginPath();
          ctx.moveTo(X - r, Y - r); ctx.lineTo(X + r, Y + r); ctx.moveTo(X - r, Y + r); ctx.lineTo(X + r, Y - r); ctx.stroke();
        }
        points.push({X: X, Y: Y, text: (s.label || "series") + "\n" + (p.x_label || "x") + " = " + valueFormat(s.x[k]) +
                     "\n" + (p.y_label || "y") + " = " + valueFormat(s.y[k])});
      }
    }
    // Lines, then the colour trail, then scatter-only series on top (as in the PNG).
    p.series.forEach(function (s) { if (s.width_px > 0) drawSeries(s); });
    var t = p.trail;
    if (t) {
      var ca = t.colour_axis;
      var colourOf = function (v) {
        var u = Math.min(1, Math.max(0, (v - ca.lo) / (ca.hi - ca.lo)));
        return t.colours[Math.round(u * 255)];
      };
      ctx.lineWidth = t.width_px; ctx.setLineDash([]);
      for (var j = 0; j + 1 < t.x.length; j++) {
        ctx.strokeStyle = colourOf(0.5 * (t.value[j] + t.value[j + 1]));
        ctx.beginPath(); ctx.moveTo(px(t.x[j]), py(t.y[j])); ctx.lineTo(px(t.x[j + 1]), py(t.y[j + 1])); ctx.stroke();
      }
      for (var q = 0; q < t.x.length; q++)
        points.push({X: px(t.x[q]), Y: py(t.y[q]), text: (p.x_label || "x") + " = " + valueFormat(t.x[q]) + "\n" +
                     (p.y_label || "y") + " = " + valueFormat(t.y[q]) + "\n" + (t.value_label || "value") + " = " + valueFormat(t.value[q])});
    }
    p.series.forEach(function (s) { if (!(s.width_px > 0)) drawSeries(s); });
    ctx.restore();
    // Frame, ticks, labels.
    ctx.strokeStyle = "#141414"; ctx.lineWidth = 1; ctx.setLineDash([]);
    ctx.strokeRect(left, top, aw, ah);
    ctx.fillStyle = "#141414"; ctx.font = "12px " + FONT;
    ctx.textAlign = "center"; ctx.textBaseline = "top";
    ticks(xa).forEach(function (v) {
      ctx.beginPath(); ctx.moveTo(px(v), top + ah); ctx.lineTo(px(v), top + ah - 6); ctx.stroke();
      ctx.fillText(tickLabel(v, xa.step), px(v), top + ah + 6);
    });
    ctx.textBaseline = "middle";
    ticks(ya).forEach(function (v) {
      ctx.beginPath(); ctx.moveTo(left, py(v)); ctx.lineTo(left + 6, py(v)); ctx.stroke();
      ctx.textAlign = "right"; ctx.fillText(tickLabel(v, ya.step), left - 6, py(v));
      if (p.right_axis) { ctx.textAlign = "left"; ctx.fillText(tickLabel(v, ya.step), left + aw + 6, py(v)); }
    });
    ctx.font = "13px " + FONT; ctx.textAlign = "center";
    if (p.x_label) ctx.fillText(p.x_label, left + aw / 2, top + ah + 8 + 12 + 8 + 8);
    if (p.y_label) { ctx.save(); ctx.translate(10 + 8, top + ah / 2); ctx.rotate(-Math.PI / 2); ctx.fillText(p.y_label, 0, 0); ctx.restore(); }
    if (p.title) { ctx.font = "14px " + FONT; ctx.fillText(p.title, left + aw / 2, 16); }
    // Legend.
    var entries = [];
    p.series.forEach(function (s) { if (s.label && !entries.some(function (e) { return e.label === s.label; })) entries.push(s); });
    p.ref_lines.forEach(function (r) { if (r.label) entries.push(r); });
    if (entries.length && p.legend !== "none") {
      ctx.font = "12px " + FONT;
      var tw = 0; entries.forEach(function (e) { tw = Math.max(tw, ctx.measureText(e.label).width); });
      var lw = 6 + 26 + 6 + tw + 6, lh = 6 + 17 * entries.length + 2;
      var lx = p.legend.indexOf("right") >= 0 ? left + aw - 8 - lw : left + 8;
      var ly = p.legend.indexOf("upper") >= 0 ? top + 8 : top + ah - 8 - lh;
      ctx.fillStyle = "#fff"; ctx.fillRect(lx, ly, lw, lh); ctx.strokeStyle = "#bebebe"; ctx.strokeRect(lx, ly, lw, lh);
      entries.forEach(function (e, i) {
        var y = ly + 6 + 17 * (i + 0.5);
        ctx.strokeStyle = e.colour; ctx.fillStyle = e.colour; ctx.lineWidth = Math.max(1.5, e.width_px || 0); dash(ctx, e.dash, e.width_px);
        if (e.width_px > 0) { ctx.beginPath(); ctx.moveTo(lx + 6, y); ctx.lineTo(lx + 32, y); ctx.stroke(); }
        if (e.marker && e.marker !== "none") ctx.fillRect(lx + 16, y - 3, 6, 6);
        ctx.setLineDash([]); ctx.fillStyle = "#141414"; ctx.textAlign = "left"; ctx.fillText(e.label, lx + 38, y);
      });
    }
    // Colour bar.
    if (t) {
      var bx = left + aw + (p.right_axis ? yw + 16 : 0) + 14, bh = Math.min(ah, Math.max(120, 0.8 * ah)), by = top + (ah - bh) / 2;
      var cax = t.colour_axis;
      for (var b = 0; b < 256; b++) { ctx.fillStyle = t.colours[b]; ctx.fillRect(bx, by + bh * (1 - (b + 1) / 256), 16, bh / 256 + 0.5); }
      ctx.strokeStyle = "#141414"; ctx.strokeRect(bx, by, 16, bh);
      ctx.fillStyle = "#141414"; ctx.font = "12px " + FONT; ctx.textAlign = "left"; ctx.textBaseline = "middle";
      var cw = 0;
      ticks(cax).forEach(function (v) {
        var y = by + bh * (1 - (v - cax.lo) / (cax.hi - cax.lo));
        ctx.fillText(tickLabel(v, cax.step), bx + 22, y);
        cw = Math.max(cw, ctx.measureText(tickLabel(v, cax.step)).width);
      });
      if (t.value_label) {
        ctx.save(); ctx.translate(bx + 22 + cw + 14, by + bh / 2); ctx.rotate(-Math.PI / 2);
        ctx.font = "13px " + FONT; ctx.textAlign = "center"; ctx.fillText(t.value_label, 0, 0); ctx.restore();
      }
    }
    canvas.dataset.points = String(points.length);
    canvas.addEventListener("mousemove", function (ev) {
      var rect = canvas.getBoundingClientRect(), mx = ev.clientX - rect.left, my = ev.clientY - rect.top, best = null, bd = 144;
      for (var i = 0; i < points.length; i++) {
        var dx = points[i].X - mx, dy = points[i].Y - my, d = dx * dx + dy * dy;
        if (d < bd) { bd = d; best = points[i]; }
      }
      if (!best) { tip.style.display = "none"; return; }
      tip.textContent = best.text; tip.style.display = "block";
      tip.style.left = (ev.clientX + 14) + "px"; tip.style.top = (ev.clientY + 14) + "px";
    });
    canvas.addEventListener("mouseleave", function () { tip.style.display = "none"; });
  }

  document.querySelectorAll(".mppi-figure").forEach(function (holder) {
    var f = figures[Number(holder.dataset.figure)];
    if (!f) return;
    if (f.title) { var h = document.createElement("div"); h.className = "mppi-figure-title"; h.textContent = f.title; holder.appendChild(h); }
    var grid = document.createElement("div");
    grid.className = "mppi-panels";
    grid.style.gridTemplateColumns = "repeat(" + f.columns + ", " + f.panel_width_px + "px)";
    holder.appendChild(grid);
    f.panels.forEach(function (p) {
      var c = document.createElement("canvas");
      grid.appendChild(c);
      drawPanel(c, p, f.panel_width_px, f.panel_height_px);
    });
    holder.dataset.drawn = String(f.panels.length);
  });
})();
