/*
 * PrintWatch tab, top panel: what the plugin is doing right now (state, next
 * check, preparation progress, camera health) and the per-file
 * "print without checks" switch. Fed by GET status and "status" push messages.
 */
$(function () {
    "use strict";

    function PrintWatchStatusViewModel(parameters) {
        var self = this;
        var fmt = PrintWatchFormat;

        self.loginState = parameters[0];
        self.access = parameters[1];

        self.status = ko.observable(null);
        self.loaded = ko.observable(false);
        self.error = ko.observable("");
        self.cameraBusy = ko.observable("");
        self.fileBusy = ko.observable(false);

        self.isAdmin = PrintWatchApi.adminComputed(self.loginState, self.access);

        self.state = ko.pureComputed(function () {
            var s = self.status();
            return s ? s.state : "";
        });
        self.stateLabel = ko.pureComputed(function () {
            var s = self.status();
            if (!s) return "";
            if (!s.enabled) return "Monitoring is switched off in the settings";
            return fmt.stateLabel(s.state);
        });
        self.stateClass = ko.pureComputed(function () {
            var s = self.status();
            if (!s || !s.enabled) return "label";
            return {
                idle: "label",
                preparing: "label label-info",
                monitoring: "label label-success",
                checking: "label label-warning",
                paused: "label label-important"
            }[s.state] || "label";
        });

        self.jobName = ko.pureComputed(function () {
            var s = self.status();
            return s && s.job ? s.job.name || s.job.path : "";
        });
        self.jobChecksEnabled = ko.pureComputed(function () {
            var s = self.status();
            return !!(s && s.job && s.job.checks_enabled);
        });
        self.jobInjected = ko.pureComputed(function () {
            var s = self.status();
            return !!(s && s.job && s.job.injected);
        });

        self.checksProgress = ko.pureComputed(function () {
            var s = self.status();
            if (!s || !s.planned_checks) return "";
            return (s.checks_done || 0) + " of " + s.planned_checks.length;
        });
        self.nextCheckText = ko.pureComputed(function () {
            var s = self.status();
            if (!s || !s.print_id) return "";
            if (!s.next_check) return "No checks left in this print";
            return "Layer " + s.next_check.layer + " (z " + fmt.mm(s.next_check.z) + ")";
        });

        self.preparation = ko.pureComputed(function () {
            var s = self.status();
            return s && s.preparation ? s.preparation : {state: "none", progress: 0, message: ""};
        });
        self.preparationVisible = ko.pureComputed(function () {
            var p = self.preparation();
            return p.state === "queued" || p.state === "rendering" || p.state === "failed";
        });
        self.preparationPercent = ko.pureComputed(function () {
            var p = self.preparation().progress;
            return Math.round(100 * Math.min(1, Math.max(0, typeof p === "number" ? p : 0)));
        });
        self.preparationText = ko.pureComputed(function () {
            var p = self.preparation();
            if (p.state === "failed") return "Preparing the expected views failed" + (p.message ? ": " + p.message : "");
            if (p.state === "queued") return "Waiting to render the expected views…";
            return "Rendering the expected views: " + self.preparationPercent() + " %" + (p.message ? " – " + p.message : "");
        });

        self.cameras = ko.pureComputed(function () {
            var s = self.status();
            return s && s.cameras ? s.cameras : [];
        });
        self.pairsText = ko.pureComputed(function () {
            var s = self.status();
            if (!s || !s.pairs || !s.pairs.length) return "";
            return s.pairs.map(function (p) {
                return p[0] + " + " + p[1];
            }).join(", ");
        });
        self.lastFailure = ko.pureComputed(function () {
            var s = self.status();
            return s && s.state === "paused" && s.last_failure ? s.last_failure : null;
        });

        self.healthClass = function (camera) {
            if (!camera.enabled) return "printwatch-dot printwatch-dot-off";
            return "printwatch-dot printwatch-dot-" + (camera.health || "unknown");
        };
        self.healthText = function (camera) {
            if (!camera.enabled) return "disabled";
            if (camera.health === "ok") return "answering" + (camera.last_seconds != null ? " (" + fmt.seconds(camera.last_seconds) + ")" : "");
            if (camera.health === "error") return camera.last_error || "not answering";
            return "not tried yet";
        };

        self.fromStatus = function (status) {
            self.status(status);
            self.loaded(true);
            self.error("");
        };

        self.requestStatus = function () {
            if (!self.loginState.isUser()) return;
            return PrintWatchApi.status().done(self.fromStatus).fail(function (xhr) {
                self.loaded(true);
                self.error(PrintWatchApi.errorText(xhr, "Could not load the PrintWatch status"));
            });
        };

        self.testCamera = function (camera) {
            self.cameraBusy(camera.name);
            PrintWatchApi.testCamera(camera.name).done(function () {
                self.requestStatus();
            }).fail(function (xhr) {
                new PNotify({title: "PrintWatch", text: PrintWatchApi.errorText(xhr, "Camera test failed"), type: "error"});
            }).always(function () {
                self.cameraBusy("");
            });
        };

        self.toggleFileChecks = function () {
            var s = self.status();
            if (!s || !s.job) return;
            self.fileBusy(true);
            PrintWatchApi.setFileChecks(s.job.origin, s.job.path, !s.job.checks_enabled).done(function () {
                self.requestStatus();
            }).fail(function (xhr) {
                new PNotify({title: "PrintWatch", text: PrintWatchApi.errorText(xhr, "Could not change the checks of this file"), type: "error"});
            }).always(function () {
                self.fileBusy(false);
            });
        };

        self.onStartupComplete = self.requestStatus;
        self.onUserLoggedIn = self.requestStatus;
        self.onUserLoggedOut = function () {
            self.status(null);
            self.loaded(false);
        };
        self.onEventSettingsUpdated = self.requestStatus;

        self.onDataUpdaterPluginMessage = function (plugin, data) {
            if (plugin !== "printwatch" || !data) return;
            if (data.type === "status" && data.status) self.fromStatus(data.status);
        };
    }

    OCTOPRINT_VIEWMODELS.push({
        construct: PrintWatchStatusViewModel,
        dependencies: ["loginStateViewModel", "accessViewModel"],
        elements: ["#printwatch_status"]
    });
});
