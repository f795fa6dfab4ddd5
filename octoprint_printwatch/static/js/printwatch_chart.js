/*
 * PrintWatch: error-against-layer charts drawn with the vendored uPlot.
 *
 * One chart shows one family of measurements (shape error % per camera, or
 * size error % per stereo pair) for one print, with a dashed line for each
 * threshold in force and a red band at every layer whose check failed.
 * Pure presentation: callers hand in plain arrays, nothing here talks to the
 * server.
 */
(function (global) {
    "use strict";

    // Colour-blind-safe palette (Okabe-Ito), repeated if there are more series.
    var PALETTE = ["#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442", "#000000"];
    var THRESHOLD_COLOUR = "#c0392b";
    var FAIL_BAND = "rgba(192, 57, 43, 0.13)";
    var UNKNOWN_BAND = "rgba(120, 120, 120, 0.12)";

    // OctoPrint wraps all of a plugin's JS in one function, so the vendored
    // library's top-level "var uPlot" is a closure variable there, and a
    // global only when the files are served one by one (debug mode).
    function uPlotClass() {
        return typeof uPlot !== "undefined" ? uPlot : global.uPlot;
    }

    function colourAt(index) {
        return PALETTE[index % PALETTE.length];
    }

    /*
     * Build the uPlot data table from checks.
     *   checks: [{layer, verdict, values: {seriesName: number|null}}]
     *   seriesNames: [string]
     * Returns [layers, values of series 0, values of series 1, ...] with null
     * where a series has no value at a layer (uPlot leaves a gap there).
     */
    function buildTable(checks, seriesNames) {
        var sorted = checks.slice().sort(function (a, b) {
            return a.layer - b.layer;
        });
        var table = [sorted.map(function (c) {
            return c.layer;
        })];
        seriesNames.forEach(function (name) {
            table.push(sorted.map(function (c) {
                var v = c.values ? c.values[name] : undefined;
                return typeof v === "number" && isFinite(v) ? v : null;
            }));
        });
        return table;
    }

    // Draws translucent bands at failed (red) and unknown (grey) layers and dashed threshold lines.
    function overlayPlugin(getBands, getThresholds) {
        return {
            hooks: {
                drawAxes: [function (u) {
                    var ctx = u.ctx;
                    var bands = getBands();
                    if (!bands.length) return;
                    var half = Math.max(3, 4 * devicePixelRatio);
                    ctx.save();
                    bands.forEach(function (band) {
                        var x = u.valToPos(band.layer, "x", true);
                        ctx.fillStyle = band.verdict === "fail" ? FAIL_BAND : UNKNOWN_BAND;
                        ctx.fillRect(x - half, u.bbox.top, 2 * half, u.bbox.height);
                    });
                    ctx.restore();
                }],
                draw: [function (u) {
                    var ctx = u.ctx;
                    var thresholds = getThresholds();
                    ctx.save();
                    ctx.strokeStyle = THRESHOLD_COLOUR;
                    ctx.fillStyle = THRESHOLD_COLOUR;
                    ctx.lineWidth = 1.5 * devicePixelRatio;
                    ctx.setLineDash([6 * devicePixelRatio, 4 * devicePixelRatio]);
                    ctx.font = (11 * devicePixelRatio) + "px sans-serif";
                    ctx.textAlign = "left";
                    thresholds.forEach(function (t) {
                        var y = Math.round(u.valToPos(t.value, "y", true));
                        if (y < u.bbox.top || y > u.bbox.top + u.bbox.height) return;
                        ctx.beginPath();
                        ctx.moveTo(u.bbox.left, y);
                        ctx.lineTo(u.bbox.left + u.bbox.width, y);
                        ctx.stroke();
                        // Label at the left end (failures tend to be at the right), on a
                        // light box so that it stays readable over points and lines.
                        var pad = 3 * devicePixelRatio;
                        var width = ctx.measureText(t.label).width;
                        var x = u.bbox.left + 6 * devicePixelRatio;
                        var top = y - 16 * devicePixelRatio;
                        ctx.save();
                        ctx.setLineDash([]);
                        ctx.fillStyle = "rgba(255, 255, 255, 0.85)";
                        ctx.fillRect(x - pad, top, width + 2 * pad, 14 * devicePixelRatio);
                        ctx.restore();
                        ctx.fillText(t.label, x, y - 5 * devicePixelRatio);
                    });
                    ctx.restore();
                }]
            }
        };
    }

    /*
     * ErrorChart(element, options)
     *   options.yLabel: axis label, e.g. "Shape error %"
     *   options.syncKey: charts with the same key share the cursor
     * update({checks, seriesNames, thresholds: [{value, label}], lastLayer})
 *   lastLayer (optional): the print's last planned check; the layer axis then spans the whole print
     */
    function ErrorChart(element, options) {
        this.element = element;
        this.options = options || {};
        this.plot = null;
        this.state = {checks: [], seriesNames: [], thresholds: []};
        this.signature = "";
    }

    ErrorChart.prototype._width = function () {
        return Math.max(320, this.element.clientWidth || 0);
    };

    ErrorChart.prototype._failedLayers = function () {
        return this.state.checks.filter(function (c) {
            return c.verdict === "fail";
        }).map(function (c) {
            return c.layer;
        });
    };

    ErrorChart.prototype._yMax = function () {
        var max = 0;
        this.state.checks.forEach(function (c) {
            Object.keys(c.values || {}).forEach(function (k) {
                var v = c.values[k];
                if (typeof v === "number" && isFinite(v)) max = Math.max(max, v);
            });
        });
        this.state.thresholds.forEach(function (t) {
            max = Math.max(max, t.value);
        });
        // Headroom above the highest value or threshold, never a flat 0..0 axis.
        return Math.max(1, Math.ceil(max * 1.2));
    };

    // The whole print when its planned checks are known (progress shows), else the data plus a margin.
    ErrorChart.prototype._xRange = function (min, max) {
        var last = this.state.lastLayer;
        if (typeof last === "number" && isFinite(last) && last > 0) {
            return [0, Math.max(last, max == null ? 0 : max)];
        }
        if (min == null || max == null) return [0, 1];
        if (min === max) return [Math.max(0, min - 1), max + 1];
        return [min, max];
    };

    ErrorChart.prototype._create = function () {
        var self = this;
        if (this.plot) {
            this.plot.destroy();
            this.plot = null;
        }
        var series = [{label: "Layer"}];
        this.state.seriesNames.forEach(function (name, i) {
            series.push({
                label: name,
                stroke: colourAt(i),
                width: 2,
                points: {show: true, size: 7, fill: colourAt(i)},
                spanGaps: false,
                value: function (u, v) {
                    return v == null ? "–" : v.toFixed(1) + " %";
                }
            });
        });
        var opts = {
            width: this._width(),
            height: this.options.height || 240,
            cursor: {sync: this.options.syncKey ? {key: this.options.syncKey} : undefined},
            legend: {live: true},
            scales: {
                x: {time: false, range: function (u, min, max) {
                    return self._xRange(min, max);
                }},
                y: {range: function () {
                    return [0, self._yMax()];
                }}
            },
            axes: [
                {label: "Layer", labelSize: 20},
                {label: this.options.yLabel || "Error %", labelSize: 20,
                    values: function (u, ticks) {
                        return ticks.map(function (t) {
                            return t + " %";
                        });
                    }}
            ],
            series: series,
            plugins: [overlayPlugin(function () {
                return self.state.checks.filter(function (c) {
                    return c.verdict === "fail" || c.verdict === "unknown";
                });
            }, function () {
                return self.state.thresholds;
            })]
        };
        var UPlot = uPlotClass();
        this.plot = new UPlot(opts, buildTable(this.state.checks, this.state.seriesNames), this.element);
    };

    ErrorChart.prototype.update = function (state) {
        this.state = {
            checks: state.checks || [],
            seriesNames: state.seriesNames || [],
            thresholds: state.thresholds || [],
            lastLayer: state.lastLayer
        };
        var signature = this.state.seriesNames.join("\u0000");
        var pointCount = 0;
        var table = buildTable(this.state.checks, this.state.seriesNames);
        for (var s = 1; s < table.length; s++) {
            pointCount += table[s].filter(function (v) {
                return v !== null;
            }).length;
        }
        // Exposed for tests and for anyone inspecting the page.
        this.element.setAttribute("data-series", this.state.seriesNames.length);
        this.element.setAttribute("data-points", pointCount);
        this.element.setAttribute("data-failed", this._failedLayers().length);
        this.element.setAttribute("data-thresholds", this.state.thresholds.map(function (t) {
            return t.value;
        }).join(","));
        if (!this.plot || signature !== this.signature) {
            this.signature = signature;
            this._create();
        } else {
            this.plot.setData(table);
        }
    };

    ErrorChart.prototype.resize = function () {
        if (this.plot && this.element.clientWidth > 0) {
            this.plot.setSize({width: this._width(), height: this.options.height || 240});
        }
    };

    ErrorChart.prototype.destroy = function () {
        if (this.plot) this.plot.destroy();
        this.plot = null;
    };

    global.PrintWatchChart = {ErrorChart: ErrorChart, buildTable: buildTable, colourAt: colourAt, available: function () {
        return !!uPlotClass();
    }};
})(window);
