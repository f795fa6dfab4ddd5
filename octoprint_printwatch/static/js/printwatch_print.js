/*
 * PrintWatch tab, one print: the error charts against layer, the latest
 * frames with the expected outline drawn over them, the table of checks, and
 * re-running the recording with other thresholds.
 *
 * Which print is shown is decided by the history view model (select()); a
 * new print started while the tab is open is followed automatically.
 */
$(function () {
    "use strict";

    function PrintWatchPrintViewModel(parameters) {
        var self = this;
        var fmt = PrintWatchFormat;

        self.loginState = parameters[0];
        self.access = parameters[1];

        self.printId = ko.observable(null);
        self.print = ko.observable(null);     // Print + checks + settings from GET prints/<id>
        self.loading = ko.observable(false);
        self.error = ko.observable("");
        // Follow the running print unless the user picked another one.
        self.followLive = true;

        // Re-run with other thresholds.
        self.rerunShape = ko.observable("");
        self.rerunSize = ko.observable("");
        self.rerunBusy = ko.observable(false);
        self.rerunError = ko.observable("");
        self.rerunResult = ko.observable(null); // evaluate answer
        self.showRerun = ko.observable(false);  // chart shows the re-run instead of the recorded checks

        self.showTable = ko.observable(false);

        self.shapeChart = null;
        self.sizeChart = null;

        self.isAdmin = PrintWatchApi.adminComputed(self.loginState, self.access);

        self.checks = ko.pureComputed(function () {
            var p = self.print();
            return p && p.checks ? p.checks : [];
        });
        self.displayedChecks = ko.pureComputed(function () {
            var r = self.rerunResult();
            return self.showRerun() && r ? r.checks || [] : self.checks();
        });
        self.hasChecks = ko.pureComputed(function () {
            return self.displayedChecks().length > 0;
        });
        // Checks ran but measured nothing (e.g. every one "unknown"): say why instead of an empty chart.
        self.noMeasurements = ko.pureComputed(function () {
            var checks = self.displayedChecks();
            if (!checks.length) return "";
            var measured = checks.some(function (c) {
                return Object.keys(c.shape_error_pct || {}).length || Object.keys(c.size || {}).length;
            });
            if (measured) return "";
            var reasons = _.uniq(_.flatten(checks.map(function (c) {
                return c.reasons || [];
            })));
            return "None of the " + checks.length + " checks could measure the part" +
                (reasons.length ? ": " + reasons.slice(0, 3).join("; ") : ".");
        });
        self.unknownCount = ko.pureComputed(function () {
            return self.displayedChecks().filter(function (c) {
                return c.verdict === "unknown";
            }).length;
        });

        // "none": no stereo pair took part; "empty": pairs ran but measured nothing; "data": something to draw.
        self.sizeState = ko.pureComputed(function () {
            var checks = self.displayedChecks();
            var hasPairs = checks.some(function (c) {
                return c.size && Object.keys(c.size).length > 0;
            });
            if (!hasPairs) return "none";
            var measured = checks.some(function (c) {
                return Object.keys(c.size || {}).some(function (k) {
                    return c.size[k] && typeof c.size[k].error_pct === "number";
                });
            });
            return measured ? "data" : "empty";
        });
        self.hasSizeData = ko.pureComputed(function () {
            return self.sizeState() === "data";
        });

        self.title = ko.pureComputed(function () {
            var p = self.print();
            if (!p) return "";
            return (p.file && (p.file.name || p.file.path)) || "Print " + p.id;
        });
        self.subtitle = ko.pureComputed(function () {
            var p = self.print();
            if (!p) return "";
            var parts = [fmt.dateTime(p.started), fmt.resultLabel(p.result)];
            var d = fmt.duration(p.started, p.ended);
            if (d) parts.push(d);
            parts.push((p.checks_done || 0) + " of " + (p.checks_planned || 0) + " checks");
            return parts.join(" · ");
        });
        // Why the print failed: the reasons of its first failed check, one per line.
        self.failureReasons = ko.pureComputed(function () {
            var p = self.print();
            if (!p || p.first_failure_layer == null) return [];
            var failed = _.find(self.checks(), function (c) {
                return c.verdict === "fail";
            });
            if (failed && failed.reasons && failed.reasons.length) return failed.reasons;
            return p.failure_reason ? [p.failure_reason] : ["The check at this layer failed."];
        });
        self.failureTitle = ko.pureComputed(function () {
            var p = self.print();
            return p ? "Failure detected at layer " + p.first_failure_layer + ":" : "";
        });
        self.recordingUrl = ko.pureComputed(function () {
            var p = self.print();
            return p && p.recording && p.recording.available ? PrintWatchApi.absolute(p.recording.url) : null;
        });
        self.recordingSize = ko.pureComputed(function () {
            var p = self.print();
            return p && p.recording ? fmt.bytes(p.recording.bytes) : "";
        });

        // Latest frames: the newest check that has at least one image.
        self.latestCheck = ko.pureComputed(function () {
            var checks = self.checks();
            for (var i = checks.length - 1; i >= 0; i--) {
                var cams = checks[i].cameras || {};
                if (Object.keys(cams).length) return checks[i];
            }
            return null;
        });
        self.latestFrames = ko.pureComputed(function () {
            var check = self.latestCheck();
            if (!check) return [];
            var cams = check.cameras || {};
            return Object.keys(cams).sort().map(function (name) {
                var cam = cams[name] || {};
                var url = cam.overlay_url || cam.frame_url;
                var error = check.shape_error_pct ? check.shape_error_pct[name] : undefined;
                var limit = check.thresholds && check.thresholds.shape_pct
                    ? (typeof check.thresholds.shape_pct === "number" ? check.thresholds.shape_pct : check.thresholds.shape_pct[name])
                    : undefined;
                return {
                    name: name,
                    url: PrintWatchApi.absolute(url),
                    isOverlay: !!cam.overlay_url,
                    status: cam.status || "ok",
                    error: cam.error,
                    shapeText: fmt.pct(error),
                    failed: typeof error === "number" && typeof limit === "number" && error > limit,
                    caption: name + " · layer " + check.layer + (typeof error === "number" ? " · shape error " + fmt.pct(error) : "") +
                        (cam.overlay_url ? "" : " · no overlay")
                };
            });
        });

        self.tableRows = ko.pureComputed(function () {
            return self.displayedChecks().map(function (c) {
                var shapes = Object.keys(c.shape_error_pct || {}).sort().map(function (k) {
                    return k + " " + fmt.pct(c.shape_error_pct[k]);
                }).join(", ");
                var sizes = Object.keys(c.size || {}).sort().map(function (k) {
                    var s = c.size[k] || {};
                    return k + " " + fmt.pct(s.error_pct) + " (w " + fmt.mm(s.width_mm) + " / " + fmt.mm(s.expected_width_mm) +
                        ", h " + fmt.mm(s.height_mm) + " / " + fmt.mm(s.expected_height_mm) + ")";
                }).join(", ");
                return {
                    layer: c.layer,
                    z: fmt.mm(c.z),
                    verdict: c.verdict,
                    verdictClass: c.verdict === "fail" ? "label label-important" : c.verdict === "ok" ? "label label-success" : "label",
                    shapes: shapes || "–",
                    sizes: sizes || "–",
                    reasons: (c.reasons || []).join("; "),
                    seconds: fmt.seconds(c.hold_seconds != null ? c.hold_seconds : c.seconds)
                };
            });
        });

        self.rerunSummary = ko.pureComputed(function () {
            var r = self.rerunResult();
            var p = self.print();
            if (!r || !p) return "";
            var was = p.first_failure_layer;
            var now = r.first_failure_layer;
            var text = now == null ? "With these thresholds no check fails" : "With these thresholds the first failure is at layer " + now;
            text += was == null ? " (recorded: no failure)." : " (recorded: layer " + was + ").";
            return text;
        });

        // ~~ data

        self.select = function (id, byUser) {
            if (byUser) self.followLive = false;
            if (id === null || id === undefined) {
                self.printId(null);
                self.print(null);
                self.redraw();
                return;
            }
            if (id !== self.printId()) {
                self.rerunResult(null);
                self.showRerun(false);
                self.rerunError("");
            }
            self.printId(id);
            self.refresh();
        };

        self.refresh = function () {
            var id = self.printId();
            if (id === null) return;
            self.loading(true);
            PrintWatchApi.print(id).done(function (print) {
                if (id !== self.printId()) return;
                self.print(print);
                self.error("");
                var settings = print.settings || {};
                if (self.rerunShape() === "" && typeof settings.shape_threshold_pct === "number") self.rerunShape(String(settings.shape_threshold_pct));
                if (self.rerunSize() === "" && typeof settings.size_threshold_pct === "number") self.rerunSize(String(settings.size_threshold_pct));
                self.redraw();
            }).fail(function (xhr) {
                self.error(PrintWatchApi.errorText(xhr, "Could not load print " + id));
            }).always(function () {
                self.loading(false);
            });
        };

        self.rerun = function () {
            var id = self.printId();
            var shape = parseFloat(self.rerunShape());
            var size = parseFloat(self.rerunSize());
            if (!(shape > 0) || !(size > 0)) {
                self.rerunError("Enter both thresholds as positive percentages.");
                return;
            }
            self.rerunBusy(true);
            self.rerunError("");
            // A single shape threshold for every camera: per-camera overrides are cleared for the re-run.
            PrintWatchApi.evaluate(id, {
                shape_threshold_pct: shape,
                shape_threshold_per_camera: {},
                size_threshold_pct: size
            }).done(function (result) {
                self.rerunResult(result);
                self.showRerun(true);
                self.redraw();
            }).fail(function (xhr) {
                self.rerunError(PrintWatchApi.errorText(xhr, "Re-running the recording failed"));
            }).always(function () {
                self.rerunBusy(false);
            });
        };

        self.showRecorded = function () {
            self.showRerun(false);
            self.redraw();
        };
        self.showRerunResult = function () {
            if (self.rerunResult()) self.showRerun(true);
            self.redraw();
        };

        // ~~ charts

        self.redraw = function () {
            var shapeEl = document.getElementById("printwatch_chart_shape");
            var sizeEl = document.getElementById("printwatch_chart_size");
            if (!shapeEl || !sizeEl) return;
            if (!PrintWatchChart.available()) {
                // No chart library (a broken install): the numbers still show.
                self.showTable(true);
                return;
            }
            var settings;
            if (self.showRerun() && self.rerunResult()) {
                settings = {
                    shape_threshold_pct: parseFloat(self.rerunShape()),
                    size_threshold_pct: parseFloat(self.rerunSize())
                };
            } else {
                settings = (self.print() || {}).settings;
            }
            var input = fmt.chartInput(self.displayedChecks(), settings);
            if (!self.shapeChart) self.shapeChart = new PrintWatchChart.ErrorChart(shapeEl, {yLabel: "Shape error", syncKey: "printwatch"});
            if (!self.sizeChart) self.sizeChart = new PrintWatchChart.ErrorChart(sizeEl, {yLabel: "Size error", syncKey: "printwatch", height: 200});
            // Charts need a visible element to measure; a hidden tab draws when it is shown (onAfterTabChange).
            if (shapeEl.offsetParent === null) return;
            var planned = ((self.print() || {}).planned_checks || []).map(function (c) {
                return c.layer;
            });
            var lastLayer = planned.length ? Math.max.apply(null, planned) : null;
            input.shape.lastLayer = lastLayer;
            input.size.lastLayer = lastLayer;
            self.shapeChart.update(input.shape);
            self.sizeChart.update(input.size);
            // The size chart may just have become visible: fit it to its width.
            self.sizeChart.resize();
        };

        self.onAfterTabChange = function (current) {
            if (current === "#tab_plugin_printwatch") {
                self.redraw();
                if (self.shapeChart) self.shapeChart.resize();
                if (self.sizeChart) self.sizeChart.resize();
            }
        };

        $(window).on("resize", _.debounce(function () {
            if (self.shapeChart) self.shapeChart.resize();
            if (self.sizeChart) self.sizeChart.resize();
        }, 200));

        self.onDataUpdaterPluginMessage = function (plugin, data) {
            if (plugin !== "printwatch" || !data) return;
            if ((data.type === "check" || data.type === "failure") && data.print_id != null) {
                if (data.print_id === self.printId()) {
                    self.refresh();
                } else if (self.followLive) {
                    self.select(data.print_id);
                }
            } else if (data.type === "status" && data.status && self.followLive) {
                var id = data.status.print_id;
                if (id != null && id !== self.printId()) self.select(id);
            }
        };
    }

    OCTOPRINT_VIEWMODELS.push({
        construct: PrintWatchPrintViewModel,
        dependencies: ["loginStateViewModel", "accessViewModel"],
        elements: ["#printwatch_print"]
    });
});
