"use strict";
// A small time plot on a canvas: several series of [t_ms, value] against the last `windowS`
// seconds, with labelled axes and a legend. Plain canvas, no library: nothing to fetch at run
// time and nothing to install.
window.TeejetPlot = class TeejetPlot {
  constructor(canvas, legend) {
    this.canvas = canvas;
    this.legend = legend;
    this.legendKey = "";
  }

  // series: [{label, color, points: [[t_ms, value], ...]}] (points oldest first); nowMs: the
  // right edge; unit: the y axis label.
  draw(series, nowMs, windowS, unit) {
    const canvas = this.canvas;
    const ratio = window.devicePixelRatio || 1;
    const width = canvas.clientWidth || canvas.width;
    const height = canvas.clientHeight || canvas.height;
    if (canvas.width !== Math.round(width * ratio) || canvas.height !== Math.round(height * ratio)) {
      canvas.width = Math.round(width * ratio);
      canvas.height = Math.round(height * ratio);
    }
    const g = canvas.getContext("2d");
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    g.clearRect(0, 0, width, height);
    const left = 52, right = 12, top = 10, bottom = 30;
    const plotW = width - left - right, plotH = height - top - bottom;
    const startMs = nowMs - windowS * 1000;

    let low = Infinity, high = -Infinity;
    for (const s of series) {
      for (const [t, v] of s.points) {
        if (t < startMs - 60000 || v === null) continue;
        low = Math.min(low, v);
        high = Math.max(high, v);
      }
    }
    if (!isFinite(low)) { low = 0; high = 1; }
    if (high - low < 1e-6) { low -= 1; high += 1; }
    const pad = (high - low) * 0.08;
    // Positions, volts and amps are never negative: no axis below zero for them.
    [low, high] = niceRange(low >= 0 ? Math.max(0, low - pad) : low - pad, high + pad);
    const x = (t) => left + ((t - startMs) / (windowS * 1000)) * plotW;
    const y = (v) => top + (1 - (v - low) / (high - low)) * plotH;

    g.font = "11px system-ui, sans-serif";
    g.strokeStyle = "#e3e6eb";
    g.fillStyle = "#6b7280";
    g.lineWidth = 1;
    g.textAlign = "right";
    g.textBaseline = "middle";
    const yStep = niceStep((high - low) / 5);
    for (let v = Math.ceil(low / yStep) * yStep; v <= high + 1e-9; v += yStep) {
      g.beginPath(); g.moveTo(left, y(v)); g.lineTo(left + plotW, y(v)); g.stroke();
      g.fillText(formatTick(v, yStep), left - 6, y(v));
    }
    g.textAlign = "center";
    g.textBaseline = "top";
    const xStep = windowS <= 60 ? 10 : windowS <= 120 ? 20 : 60;
    for (let s = 0; s <= windowS; s += xStep) {
      const px = x(nowMs - s * 1000);
      g.beginPath(); g.moveTo(px, top); g.lineTo(px, top + plotH); g.stroke();
      g.fillText(s === 0 ? "now" : `−${s} s`, px, top + plotH + 4);
    }
    g.strokeStyle = "#9aa4b2";
    g.strokeRect(left, top, plotW, plotH);
    g.save();
    g.translate(12, top + plotH / 2);
    g.rotate(-Math.PI / 2);
    g.textBaseline = "middle";
    g.fillText(unit, 0, 0);
    g.restore();

    g.save();
    g.beginPath();
    g.rect(left, top, plotW, plotH);
    g.clip();
    g.lineWidth = 2;
    for (const s of series) {
      g.strokeStyle = s.color;
      g.beginPath();
      let drawing = false, last = null;
      for (const [t, v] of s.points) {
        if (v === null) { drawing = false; continue; }
        // A value holds until the next one: step, as the valve reported it.
        if (drawing) g.lineTo(x(t), y(last));
        drawing ? g.lineTo(x(t), y(v)) : g.moveTo(x(t), y(v));
        drawing = true;
        last = v;
      }
      if (drawing) g.lineTo(x(nowMs), y(last));
      g.stroke();
    }
    g.restore();
    this.drawLegend(series);
  }

  drawLegend(series) {
    const key = series.map((s) => s.label + s.color).join("|");
    if (key === this.legendKey) return;
    this.legendKey = key;
    this.legend.replaceChildren(...series.map((s) => {
      const item = document.createElement("span");
      const swatch = document.createElement("span");
      swatch.className = "swatch";
      swatch.style.background = s.color;
      item.append(swatch, s.label);
      return item;
    }));
    if (series.length === 0) this.legend.textContent = "no valve ticked";
  }
};

function niceStep(raw) {
  const power = Math.pow(10, Math.floor(Math.log10(raw)));
  const f = raw / power;
  return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * power;
}

function niceRange(low, high) {
  const step = niceStep((high - low) / 5);
  return [Math.floor(low / step) * step, Math.ceil(high / step) * step];
}

function formatTick(v, step) {
  return step >= 1 ? v.toFixed(0) : v.toFixed(Math.min(3, Math.ceil(-Math.log10(step))));
}
