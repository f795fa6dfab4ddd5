/*
 * PrintWatch failure popup: when a check fails ("failure" push message) a
 * dialog shows why, with the frames of the cameras that saw it, and offers to
 * resume or cancel the print. "notice" messages become notifications.
 */
$(function () {
    "use strict";

    function PrintWatchFailureViewModel(parameters) {
        var self = this;
        var fmt = PrintWatchFormat;

        self.loginState = parameters[0];
        self.printerState = parameters[1];

        self.message = ko.observable("");
        self.action = ko.observable("");
        self.reasons = ko.observableArray([]);
        self.frames = ko.observableArray([]);
        self.layerText = ko.observable("");
        self.busy = ko.observable(false);

        self.dialog = undefined;

        // With the reasons listed below it, the headline only says where; without them, the whole message.
        self.headline = ko.pureComputed(function () {
            if (!self.reasons().length || !self.layerText()) return self.message();
            var verb = {pause: "paused", cancel: "cancelled"}[self.action()];
            return verb ? "PrintWatch " + verb + " the print at " + self.layerText().toLowerCase() + ":"
                : "A check failed at " + self.layerText().toLowerCase() + ":";
        });

        self.actionText = ko.pureComputed(function () {
            return {
                pause: "The print is paused. Look at the printer, then resume or cancel.",
                cancel: "The print was cancelled.",
                notify: "The print goes on (action on failure: notify only)."
            }[self.action()] || "";
        });
        self.canResume = ko.pureComputed(function () {
            return self.action() === "pause" && self.printerState.isPaused();
        });
        self.canCancel = ko.pureComputed(function () {
            return self.action() !== "cancel" && (self.printerState.isPaused() || self.printerState.isPrinting());
        });

        self.show = function (data) {
            var check = data.check || {};
            self.message(data.message || "PrintWatch detected a failed print.");
            self.action(data.action || check.action || "");
            self.reasons(check.reasons || []);
            self.layerText(check.layer != null ? "Layer " + check.layer + " (z " + fmt.mm(check.z) + ")" : "");
            var cams = check.cameras || {};
            self.frames(Object.keys(cams).sort().filter(function (name) {
                return cams[name] && (cams[name].overlay_url || cams[name].frame_url);
            }).map(function (name) {
                var shape = check.shape_error_pct ? check.shape_error_pct[name] : undefined;
                return {
                    name: name,
                    url: PrintWatchApi.absolute(cams[name].overlay_url || cams[name].frame_url),
                    caption: name + " · shape error " + fmt.pct(shape)
                };
            }));
            if (self.dialog) self.dialog.modal("show");
        };

        self.resume = function () {
            self.busy(true);
            OctoPrint.job.resume().always(function () {
                self.busy(false);
                self.dialog.modal("hide");
            });
        };
        self.cancel = function () {
            self.busy(true);
            OctoPrint.job.cancel().always(function () {
                self.busy(false);
                self.dialog.modal("hide");
            });
        };
        self.openTab = function () {
            self.dialog.modal("hide");
            $('#tabs a[href="#tab_plugin_printwatch"]').tab("show");
        };

        self.onStartup = function () {
            self.dialog = $("#printwatch_failure_dialog");
        };

        self.onDataUpdaterPluginMessage = function (plugin, data) {
            if (plugin !== "printwatch" || !data) return;
            if (data.type === "failure") {
                self.show(data);
            } else if (data.type === "notice" && data.message) {
                new PNotify({
                    title: "PrintWatch",
                    text: data.message,
                    type: {error: "error", warning: "notice", info: "info"}[data.level] || "info",
                    hide: data.level !== "error"
                });
            }
        };
    }

    OCTOPRINT_VIEWMODELS.push({
        construct: PrintWatchFailureViewModel,
        dependencies: ["loginStateViewModel", "printerStateViewModel"],
        elements: ["#printwatch_failure_dialog"]
    });
});
