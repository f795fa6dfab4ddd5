/*
 * PrintWatch: small text formatting helpers shared by the view models, and
 * the conversion of the API's check objects into chart input.
 */
(function (global) {
    "use strict";

    function pct(value) {
        return typeof value === "number" && isFinite(value) ? value.toFixed(1) + " %" : "–";
    }

    function mm(value) {
        return typeof value === "number" && isFinite(value) ? value.toFixed(1) + " mm" : "–";
    }

    function seconds(value) {
        return typeof value === "number" && isFinite(value) ? value.toFixed(2) + " s" : "–";
    }

    function bytes(value) {
        if (typeof value !== "number" || !isFinite(value)) return "–";
        if (value < 1024) return value + " B";
        if (value < 1024 * 1024) return (value / 1024).toFixed(0) + " KB";
        return (value / 1024 / 1024).toFixed(1) + " MB";
    }

    function dateTime(iso) {
        if (!iso) return "–";
        var d = new Date(iso);
        if (isNaN(d.getTime())) return iso;
        return d.toLocaleString();
    }

    function duration(startIso, endIso) {
        if (!startIso || !endIso) return "";
        var s = (new Date(endIso) - new Date(startIso)) / 1000;
        if (!isFinite(s) || s < 0) return "";
        if (s < 60) return Math.round(s) + " s";
        var h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60);
        return h ? h + " h " + m + " min" : m + " min";
    }

    var RESULT_LABELS = {
        running: "Printing",
        done: "Completed",
        paused: "Paused",
        cancelled: "Cancelled",
        failed: "Failed",
        interrupted: "Interrupted"
    };

    var STATE_LABELS = {
        idle: "Idle – no print running",
        preparing: "Printing – still preparing the expected views",
        monitoring: "Printing – monitoring",
        checking: "Checking the print now",
        paused: "Print paused by PrintWatch"
    };

    // Sorted names of every camera / pair that has a value in any check.
    function seriesNames(checks, pick) {
        var names = {};
        checks.forEach(function (c) {
            Object.keys(pick(c) || {}).forEach(function (k) {
                names[k] = true;
            });
        });
        return Object.keys(names).sort();
    }

    /*
     * Chart input from API checks (print detail or an evaluate answer).
     * Returns {shape: {checks, seriesNames, thresholds}, size: {...}}.
     */
    function chartInput(checks, fallbackSettings) {
        checks = checks || [];
        var shapeNames = seriesNames(checks, function (c) {
            return c.shape_error_pct;
        });
        var sizeNames = seriesNames(checks, function (c) {
            return c.size;
        });

        var shapeChecks = checks.map(function (c) {
            return {layer: c.layer, verdict: c.verdict, values: c.shape_error_pct || {}};
        });
        var sizeChecks = checks.map(function (c) {
            var values = {};
            Object.keys(c.size || {}).forEach(function (pair) {
                var entry = c.size[pair];
                values[pair] = entry && typeof entry.error_pct === "number" ? entry.error_pct : null;
            });
            return {layer: c.layer, verdict: c.verdict, values: values};
        });

        // The thresholds of the newest check are the ones in force; fall back
        // to the print's settings when no check carries them.
        var last = checks.length ? checks[checks.length - 1] : null;
        var thresholds = (last && last.thresholds) || {};
        var settings = fallbackSettings || {};
        var shapeDefault = typeof settings.shape_threshold_pct === "number" ? settings.shape_threshold_pct : null;
        var shapeLines = [];
        var byValue = {};
        var perCamera = thresholds.shape_pct;
        if (perCamera && typeof perCamera === "object") {
            Object.keys(perCamera).sort().forEach(function (cam) {
                var v = perCamera[cam];
                if (typeof v !== "number") return;
                (byValue[v] = byValue[v] || []).push(cam);
            });
        } else if (typeof perCamera === "number") {
            byValue[perCamera] = [];
        } else if (shapeDefault !== null) {
            byValue[shapeDefault] = [];
            var overrides = settings.shape_threshold_per_camera || {};
            Object.keys(overrides).forEach(function (cam) {
                if (typeof overrides[cam] === "number") (byValue[overrides[cam]] = byValue[overrides[cam]] || []).push(cam);
            });
        }
        var distinct = Object.keys(byValue);
        distinct.forEach(function (v) {
            var value = parseFloat(v);
            var cams = byValue[v];
            var label = distinct.length > 1 && cams.length ? "limit " + cams.join(", ") + " " + value + " %" : "limit " + value + " %";
            shapeLines.push({value: value, label: label});
        });

        var sizeLimit = typeof thresholds.size_pct === "number" ? thresholds.size_pct
            : typeof settings.size_threshold_pct === "number" ? settings.size_threshold_pct : null;

        return {
            shape: {checks: shapeChecks, seriesNames: shapeNames, thresholds: shapeLines},
            size: {
                checks: sizeChecks,
                seriesNames: sizeNames,
                thresholds: sizeLimit === null ? [] : [{value: sizeLimit, label: "limit " + sizeLimit + " %"}]
            }
        };
    }

    global.PrintWatchFormat = {
        pct: pct,
        mm: mm,
        seconds: seconds,
        bytes: bytes,
        dateTime: dateTime,
        duration: duration,
        resultLabel: function (r) {
            return RESULT_LABELS[r] || r || "–";
        },
        stateLabel: function (s) {
            return STATE_LABELS[s] || s || "–";
        },
        chartInput: chartInput
    };
})(window);
