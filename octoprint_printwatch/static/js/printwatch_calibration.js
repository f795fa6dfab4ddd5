/*
 * PrintWatch calibration wizard (a dialog): pick a camera, capture frames of
 * the printed board from the browser, run the calibration, look at the RMS
 * reprojection error and the verdict, save. All the work happens on the
 * server (calibration endpoints in docs/plugin-api.md).
 */
$(function () {
    "use strict";

    var PREVIEW_INTERVAL_MS = 2000;

    function PrintWatchCalibrationViewModel(parameters) {
        var self = this;

        self.loginState = parameters[0];

        self.cameras = ko.observableArray([]);
        self.camera = ko.observable("");
        self.session = ko.observable(null);
        self.board = ko.observable(null);
        self.boardUrl = ko.observable("");
        self.previewUrl = ko.observable("");
        self.previewError = ko.observable("");
        self.busy = ko.observable("");     // what is running: "capture", "compute", "save", ""
        self.error = ko.observable("");
        self.saved = ko.observable(false);

        self.dialog = undefined;
        self.previewTimer = null;

        self.frames = ko.pureComputed(function () {
            var s = self.session();
            return s && s.frames ? s.frames.map(function (f) {
                return {
                    index: f.index,
                    detected: !!f.detected,
                    text: f.detected ? f.corners + " corners" : "no board found",
                    url: PrintWatchApi.absolute(f.image_url)
                };
            }) : [];
        });
        self.usable = ko.pureComputed(function () {
            return self.frames().filter(function (f) {
                return f.detected;
            }).length;
        });
        self.needed = ko.pureComputed(function () {
            var s = self.session();
            return s && s.needed ? s.needed : 10;
        });
        self.progressText = ko.pureComputed(function () {
            return self.usable() + " of " + self.needed() + " frames with the board found";
        });
        self.progressPercent = ko.pureComputed(function () {
            return Math.min(100, Math.round(100 * self.usable() / self.needed()));
        });
        self.canCompute = ko.pureComputed(function () {
            return self.usable() >= self.needed() && !self.busy();
        });
        self.result = ko.pureComputed(function () {
            var s = self.session();
            return s && s.result ? s.result : null;
        });
        self.verdictClass = ko.pureComputed(function () {
            var r = self.result();
            if (!r) return "";
            return {good: "alert alert-success", acceptable: "alert alert-info", poor: "alert alert-error"}[r.verdict] || "alert";
        });
        self.verdictText = ko.pureComputed(function () {
            var r = self.result();
            if (!r) return "";
            var label = {good: "Good", acceptable: "Acceptable", poor: "Poor – capture more varied frames and try again"}[r.verdict] || r.verdict;
            return label;
        });
        self.rmsText = ko.pureComputed(function () {
            var r = self.result();
            return r && typeof r.rms_px === "number" ? r.rms_px.toFixed(2) + " px" : "";
        });

        self.bedRmsText = ko.pureComputed(function () {
            var r = self.result();
            return r && typeof r.bed_rms_px === "number" ? r.bed_rms_px.toFixed(2) + " px" : "";
        });

        self.fail = function (what) {
            return function (xhr) {
                self.error(PrintWatchApi.errorText(xhr, what));
            };
        };

        self.open = function (cameraName) {
            self.error("");
            self.saved(false);
            self.session(null);
            PrintWatchApi.cameras().done(function (answer) {
                self.cameras((answer.cameras || []).map(function (c) {
                    return {name: c.name, text: (c.label || c.name) + (c.calibrated ? " (calibrated)" : "")};
                }));
                var wanted = cameraName || self.camera() || (self.cameras()[0] || {}).name || "";
                self.camera(wanted);
                if (!wanted) self.error("No cameras yet: add one in the PrintWatch settings (or in OctoPrint's webcam settings) and save.");
            }).fail(self.fail("Could not list the cameras"));
            PrintWatchApi.calibrationBoard().done(function (answer) {
                self.board(answer.board || null);
                self.boardUrl(PrintWatchApi.absolute(answer.image_url));
            });
            self.dialog.modal("show");
        };

        self.loadSession = function () {
            var cam = self.camera();
            if (!cam) return;
            PrintWatchApi.calibration(cam).done(function (s) {
                if (cam === self.camera()) self.session(s);
            }).fail(self.fail("Could not load the calibration of " + cam));
        };
        self.camera.subscribe(function () {
            self.session(null);
            self.saved(false);
            self.error("");
            self.loadSession();
            self.refreshPreview();
        });

        self.refreshPreview = function () {
            var cam = self.camera();
            if (!cam || !self.dialog || !self.dialog.hasClass("in")) return;
            // Load into an off-screen image first so the preview never flashes empty.
            var url = PrintWatchApi.snapshotUrl(cam);
            var img = new Image();
            img.onload = function () {
                self.previewUrl(url);
                self.previewError("");
            };
            img.onerror = function () {
                self.previewError("No picture from " + cam + " (is it connected?)");
            };
            img.src = url;
        };

        self.capture = function () {
            self.busy("capture");
            self.error("");
            PrintWatchApi.captureCalibrationFrame(self.camera()).done(function (s) {
                self.session(s);
                var last = s.frames && s.frames.length ? s.frames[s.frames.length - 1] : null;
                if (last && !last.detected) self.error("The board was not found in that frame: show all of it, well lit, and try again.");
            }).fail(self.fail("Capturing a frame failed")).always(function () {
                self.busy("");
            });
        };
        self.removeFrame = function (frame) {
            PrintWatchApi.deleteCalibrationFrame(self.camera(), frame.index).done(self.session).fail(self.fail("Could not delete the frame"));
        };
        self.reset = function () {
            PrintWatchApi.resetCalibration(self.camera()).done(function (s) {
                self.session(s);
                self.saved(false);
            }).fail(self.fail("Could not start over"));
        };
        self.compute = function () {
            self.busy("compute");
            self.error("");
            self.saved(false);
            PrintWatchApi.computeCalibration(self.camera()).done(function (result) {
                var s = $.extend({}, self.session() || {}, {result: result});
                self.session(s);
            }).fail(self.fail("Calibration failed")).always(function () {
                self.busy("");
            });
        };
        self.save = function () {
            self.busy("save");
            PrintWatchApi.saveCalibration(self.camera()).done(function () {
                self.saved(true);
            }).fail(self.fail("Saving the calibration failed")).always(function () {
                self.busy("");
            });
        };

        self.onStartup = function () {
            self.dialog = $("#printwatch_calibration_dialog");
            self.dialog.on("shown", function () {
                self.refreshPreview();
                self.previewTimer = setInterval(self.refreshPreview, PREVIEW_INTERVAL_MS);
            });
            self.dialog.on("hidden", function () {
                clearInterval(self.previewTimer);
                self.previewTimer = null;
            });
        };
    }

    OCTOPRINT_VIEWMODELS.push({
        construct: PrintWatchCalibrationViewModel,
        dependencies: ["loginStateViewModel"],
        elements: ["#printwatch_calibration_dialog"]
    });
});
