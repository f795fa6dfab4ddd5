/*
 * PrintWatch settings pane. Scalar settings are bound straight to OctoPrint's
 * settings model (settings.plugins.printwatch.*); the camera list, stereo
 * pairs and per-camera thresholds are edited here as rows and written back
 * just before OctoPrint saves.
 */
$(function () {
    "use strict";

    // Settings typed into number inputs come back as strings; the server wants numbers.
    var FLOAT_KEYS = ["every_mm", "lift_mm", "retract_mm", "shape_threshold_pct", "size_threshold_pct",
        "camera_timeout_s", "recording_max_mb"];
    var INT_KEYS = ["every_layers", "history_keep_prints"];
    var NULLABLE_FLOAT_KEYS = ["park_x", "park_y"];

    function toNumber(value, integer) {
        if (typeof value === "number") return value;
        var n = integer ? parseInt(value, 10) : parseFloat(value);
        return isFinite(n) ? n : null;
    }

    function CameraRow(data, overrides) {
        var self = this;
        data = data || {};
        self.name = ko.observable(data.name || "");
        self.label = ko.observable(data.label || "");
        self.type = ko.observable(data.type || "url");
        self.url = ko.observable(data.url || "");
        self.device = ko.observable(data.device != null ? String(data.device) : "0");
        self.enabled = ko.observable(data.enabled !== false);
        self.shapeLimit = ko.observable(overrides && overrides[data.name] != null ? String(overrides[data.name]) : "");
        self.problem = ko.pureComputed(function () {
            if (!/^[A-Za-z0-9_-]+$/.test(self.name())) return "Name: letters, digits, - and _ only";
            if (self.type() === "url" && !/^https?:\/\/.+/.test(self.url())) return "Snapshot URL must start with http:// or https://";
            if (self.type() === "device" && !/^\d+$/.test(self.device())) return "Device: a number such as 0 for /dev/video0";
            if (self.shapeLimit() !== "" && !(parseFloat(self.shapeLimit()) > 0)) return "Shape limit must be a positive percentage";
            return "";
        });
        self.toSettings = function () {
            var out = {name: self.name(), label: self.label(), type: self.type(), enabled: !!self.enabled()};
            if (self.type() === "url") out.url = self.url();
            else out.device = parseInt(self.device(), 10);
            return out;
        };
    }

    // A camera PrintWatch does not own (one of OctoPrint's webcams): only its threshold is editable here.
    function KnownCameraRow(camera, overrides) {
        this.name = camera.name;
        this.label = camera.label || camera.name;
        this.calibrated = !!camera.calibrated;
        this.health = camera.health || "unknown";
        this.sourceText = {octoprint: "OctoPrint webcam", url: "snapshot URL", device: "local device"}[camera.source] || camera.source || "";
        this.shapeLimit = ko.observable(overrides && overrides[camera.name] != null ? String(overrides[camera.name]) : "");
    }

    function PairRow(pair) {
        this.left = ko.observable(pair ? pair[0] : "");
        this.right = ko.observable(pair ? pair[1] : "");
    }

    function PrintWatchSettingsViewModel(parameters) {
        var self = this;

        self.settingsView = parameters[0];
        self.calibration = parameters[1];

        self.pw = null; // settings.plugins.printwatch, set before binding
        self.ownCameras = ko.observableArray([]);
        self.octoprintCameras = ko.observableArray([]);
        self.pairs = ko.observableArray([]);
        self.camerasError = ko.observable("");
        self.camerasLoading = ko.observable(false);
        self.serverCameras = ko.observableArray([]);

        self.cameraNames = ko.pureComputed(function () {
            var names = self.octoprintCameras().map(function (c) {
                return c.name;
            });
            self.ownCameras().forEach(function (c) {
                if (c.name() && names.indexOf(c.name()) < 0) names.push(c.name());
            });
            return names;
        });

        self.problems = ko.pureComputed(function () {
            var out = [];
            var seen = {};
            self.cameraNames().forEach(function (n) {
                seen[n] = (seen[n] || 0) + 1;
            });
            self.ownCameras().forEach(function (c) {
                if (c.problem()) out.push((c.name() || "New camera") + ": " + c.problem());
                if (seen[c.name()] > 1 || self.octoprintCameras().some(function (k) {
                    return k.name === c.name();
                })) out.push(c.name() + ": another camera has this name");
            });
            self.pairs().forEach(function (p, i) {
                if (!p.left() || !p.right()) out.push("Stereo pair " + (i + 1) + ": choose both cameras");
                else if (p.left() === p.right()) out.push("Stereo pair " + (i + 1) + ": left and right must be different cameras");
            });
            return _.uniq(out);
        });

        self.intervalIsLayers = ko.pureComputed(function () {
            return self.pw && self.pw.interval_mode() === "layers";
        });

        self.addCamera = function () {
            var n = 1;
            while (self.cameraNames().indexOf("cam" + n) >= 0) n++;
            self.ownCameras.push(new CameraRow({name: "cam" + n, type: "url", enabled: true}, {}));
        };
        self.removeCamera = function (row) {
            self.ownCameras.remove(row);
        };
        self.addPair = function () {
            var names = self.cameraNames();
            self.pairs.push(new PairRow([names[0] || "", names[1] || ""]));
        };
        self.removePair = function (row) {
            self.pairs.remove(row);
        };

        self.openCalibration = function (name) {
            self.calibration.open(typeof name === "string" ? name : undefined);
        };

        // True while the settings dialog shows our rows: other code saves settings too
        // (wizards, plugins), and then there is nothing of ours to write back.
        self.rowsLoaded = false;

        self.loadRows = function () {
            var pw = self.pw;
            self.rowsLoaded = true;
            var overrides = ko.mapping.toJS(pw.shape_threshold_per_camera) || {};
            var own = ko.mapping.toJS(pw.cameras) || [];
            self.ownCameras(own.map(function (c) {
                return new CameraRow(c, overrides);
            }));
            self.pairs((ko.mapping.toJS(pw.pairs) || []).map(function (p) {
                return new PairRow(p);
            }));
            self.camerasLoading(true);
            PrintWatchApi.cameras().done(function (answer) {
                var ownNames = own.map(function (c) {
                    return c.name;
                });
                self.serverCameras(answer.cameras || []);
                self.octoprintCameras((answer.cameras || []).filter(function (c) {
                    return ownNames.indexOf(c.name) < 0;
                }).map(function (c) {
                    return new KnownCameraRow(c, overrides);
                }));
                self.camerasError("");
            }).fail(function (xhr) {
                self.camerasError(PrintWatchApi.errorText(xhr, "Could not list the cameras"));
            }).always(function () {
                self.camerasLoading(false);
            });
        };

        self.cameraStatus = function (name) {
            var cam = _.find(self.serverCameras(), function (c) {
                return c.name === name;
            });
            if (!cam) return "not saved yet";
            return (cam.calibrated ? "calibrated" : "not calibrated") + ", " + (cam.health === "ok" ? "answering" : cam.health === "error" ? "not answering" : "not tried");
        };

        self.onBeforeBinding = function () {
            self.pw = self.settingsView.settings.plugins.printwatch;
        };

        self.onSettingsShown = self.loadRows;
        self.onSettingsHidden = function () {
            self.rowsLoaded = false;
        };

        self.onSettingsBeforeSave = function () {
            var pw = self.pw;
            FLOAT_KEYS.forEach(function (k) {
                if (ko.isObservable(pw[k])) {
                    var v = toNumber(pw[k](), false);
                    if (v !== null) pw[k](v);
                }
            });
            INT_KEYS.forEach(function (k) {
                if (ko.isObservable(pw[k])) {
                    var v = toNumber(pw[k](), true);
                    if (v !== null) pw[k](v);
                }
            });
            NULLABLE_FLOAT_KEYS.forEach(function (k) {
                if (ko.isObservable(pw[k])) {
                    var raw = pw[k]();
                    pw[k](raw === "" || raw === null || raw === undefined ? null : toNumber(raw, false));
                }
            });

            if (!self.rowsLoaded || !ko.isObservable(pw.cameras)) return;
            // Rows with problems are still saved as typed: nothing the user entered is lost.
            pw.cameras(self.ownCameras().map(function (c) {
                return c.toSettings();
            }));
            pw.pairs(self.pairs().filter(function (p) {
                return p.left() && p.right();
            }).map(function (p) {
                return [p.left(), p.right()];
            }));
            // A cleared override is sent as null: OctoPrint only sends changed keys,
            // so a missing key would leave the old override in place. Cameras without
            // a row here (the camera list did not load) keep theirs.
            var overrides = ko.mapping.toJS(pw.shape_threshold_per_camera) || {};
            self.octoprintCameras().concat(self.ownCameras()).forEach(function (row) {
                var name = ko.unwrap(row.name);
                var v = parseFloat(row.shapeLimit());
                if (name) overrides[name] = v > 0 ? v : null;
            });
            pw.shape_threshold_per_camera = overrides;
        };
    }

    OCTOPRINT_VIEWMODELS.push({
        construct: PrintWatchSettingsViewModel,
        dependencies: ["settingsViewModel", "printWatchCalibrationViewModel"],
        elements: ["#settings_plugin_printwatch"]
    });
});
