/*
 * PrintWatch tab, history: the monitored prints, newest first, with their
 * result, the first failure, a download link for the recording, and
 * selecting which print the charts show.
 */
$(function () {
    "use strict";

    var PAGE = 20;

    function PrintWatchHistoryViewModel(parameters) {
        var self = this;
        var fmt = PrintWatchFormat;

        self.loginState = parameters[0];
        self.access = parameters[1];
        self.printView = parameters[2];

        self.prints = ko.observableArray([]);
        self.total = ko.observable(0);
        self.offset = ko.observable(0);
        self.loaded = ko.observable(false);
        self.error = ko.observable("");

        self.isAdmin = PrintWatchApi.adminComputed(self.loginState, self.access);

        self.rows = ko.pureComputed(function () {
            var selected = self.printView.printId();
            return self.prints().map(function (p) {
                var failed = p.first_failure_layer != null;
                return {
                    id: p.id,
                    name: (p.file && (p.file.name || p.file.path)) || "Print " + p.id,
                    started: fmt.dateTime(p.started),
                    result: fmt.resultLabel(p.result),
                    resultClass: failed || p.result === "paused" || p.result === "failed" ? "label label-important"
                        : p.result === "done" ? "label label-success"
                        : p.result === "running" ? "label label-info" : "label",
                    checks: (p.checks_done || 0) + " / " + (p.checks_planned || 0),
                    failure: failed ? "layer " + p.first_failure_layer : "–",
                    failureReason: p.failure_reason || "",
                    recordingUrl: p.recording && p.recording.available ? PrintWatchApi.absolute(p.recording.url) : null,
                    recordingSize: p.recording ? fmt.bytes(p.recording.bytes) : "",
                    selected: p.id === selected
                };
            });
        });

        self.pageText = ko.pureComputed(function () {
            if (!self.total()) return "";
            return (self.offset() + 1) + "–" + (self.offset() + self.prints().length) + " of " + self.total();
        });
        self.hasPrev = ko.pureComputed(function () {
            return self.offset() > 0;
        });
        self.hasNext = ko.pureComputed(function () {
            return self.offset() + self.prints().length < self.total();
        });

        self.request = function () {
            if (!self.loginState.isUser()) return;
            return PrintWatchApi.prints(PAGE, self.offset()).done(function (answer) {
                self.prints(answer.prints || []);
                self.total(answer.total || 0);
                self.loaded(true);
                self.error("");
                // Show the newest print when nothing is selected yet.
                if (self.printView.printId() === null && self.prints().length && self.offset() === 0) {
                    self.printView.select(self.prints()[0].id);
                }
            }).fail(function (xhr) {
                self.loaded(true);
                self.error(PrintWatchApi.errorText(xhr, "Could not load the print history"));
            });
        };

        self.open = function (row) {
            self.printView.select(row.id, true);
        };
        self.prev = function () {
            self.offset(Math.max(0, self.offset() - PAGE));
            self.request();
        };
        self.next = function () {
            self.offset(self.offset() + PAGE);
            self.request();
        };

        self.remove = function (row) {
            showConfirmationDialog({
                title: "Delete this print's history?",
                message: "The checks and the recording of \"" + row.name + "\" (" + row.started + ") will be deleted.",
                proceed: "Delete",
                onproceed: function () {
                    PrintWatchApi.deletePrint(row.id).done(function () {
                        if (self.printView.printId() === row.id) self.printView.select(null);
                        self.request();
                    }).fail(function (xhr) {
                        new PNotify({title: "PrintWatch", text: PrintWatchApi.errorText(xhr, "Could not delete the print"), type: "error"});
                    });
                }
            });
        };

        self.onStartupComplete = self.request;
        self.onUserLoggedIn = self.request;
        self.onUserLoggedOut = function () {
            self.prints([]);
            self.loaded(false);
        };

        // A finished check changes the counts; a status change may start or end a print.
        var requestSoon = _.debounce(self.request, 500);
        var lastStatusKey = "";
        self.onDataUpdaterPluginMessage = function (plugin, data) {
            if (plugin !== "printwatch" || !data) return;
            if (data.type === "check" || data.type === "failure") {
                requestSoon();
            } else if (data.type === "status" && data.status) {
                // Preparation progress arrives often; only a new print or state matters here.
                var key = data.status.print_id + "/" + data.status.state;
                if (key !== lastStatusKey) {
                    lastStatusKey = key;
                    requestSoon();
                }
            }
        };
    }

    OCTOPRINT_VIEWMODELS.push({
        construct: PrintWatchHistoryViewModel,
        dependencies: ["loginStateViewModel", "accessViewModel", "printWatchPrintViewModel"],
        elements: ["#printwatch_history"]
    });
});
