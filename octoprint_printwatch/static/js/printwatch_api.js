/*
 * PrintWatch: the only place that knows the plugin's HTTP API
 * (docs/plugin-api.md, "printwatch-api/1"). View models call these functions
 * and never build URLs themselves.
 *
 * Every function returns the jQuery promise of OctoPrint's JS client, which
 * adds the session cookie and the CSRF header the blueprint needs.
 */
(function (global) {
    "use strict";

    var PLUGIN = "printwatch";

    function base() {
        return OctoPrint.getBlueprintUrl(PLUGIN);
    }

    function enc(path) {
        // Keep "/" in file paths; escape everything else.
        return String(path).split("/").map(encodeURIComponent).join("/");
    }

    // Absolute URL for an image/download path the server returned (relative to the blueprint).
    function absolute(relative) {
        if (!relative) return null;
        if (/^https?:\/\//.test(relative)) return relative;
        return OctoPrint.getBaseUrl() + base() + relative;
    }

    // One line of text out of a failed request, for showing to the user.
    function errorText(xhr, fallback) {
        if (xhr && xhr.responseJSON && xhr.responseJSON.error) return xhr.responseJSON.error;
        if (xhr && xhr.status === 403) return "Not allowed: log in as a user with the PrintWatch permission.";
        if (xhr && xhr.status === 404) return (fallback || "Request failed") + ": not found (is the PrintWatch plugin loaded?).";
        if (xhr && xhr.status === 0) return (fallback || "Request failed") + ": OctoPrint did not answer.";
        var status = xhr && xhr.status ? " (HTTP " + xhr.status + ")" : "";
        return (fallback || "Request failed") + status + ".";
    }

    // Whether the logged-in user may change things (PLUGIN_PRINTWATCH_ADMIN); a pureComputed.
    function adminComputed(loginState, access) {
        return ko.pureComputed(function () {
            var perms = access.permissions;
            return !!(perms && perms.PLUGIN_PRINTWATCH_ADMIN && loginState.hasPermission(perms.PLUGIN_PRINTWATCH_ADMIN));
        });
    }

    global.PrintWatchApi = {
        absolute: absolute,
        errorText: errorText,
        adminComputed: adminComputed,

        status: function () {
            return OctoPrint.get(base() + "status");
        },
        prints: function (limit, offset) {
            return OctoPrint.getWithQuery(base() + "prints", {limit: limit || 50, offset: offset || 0});
        },
        print: function (id) {
            return OctoPrint.get(base() + "prints/" + encodeURIComponent(id));
        },
        deletePrint: function (id) {
            return OctoPrint.delete(base() + "prints/" + encodeURIComponent(id));
        },
        evaluate: function (id, settings) {
            return OctoPrint.postJson(base() + "prints/" + encodeURIComponent(id) + "/evaluate", {settings: settings});
        },

        cameras: function () {
            return OctoPrint.get(base() + "cameras");
        },
        testCamera: function (name) {
            return OctoPrint.postJson(base() + "cameras/" + encodeURIComponent(name) + "/test", {});
        },
        snapshotUrl: function (name) {
            return absolute("cameras/" + encodeURIComponent(name) + "/snapshot") + "?t=" + Date.now();
        },

        fileChecks: function (origin, path) {
            return OctoPrint.get(base() + "files/" + encodeURIComponent(origin) + "/" + enc(path));
        },
        setFileChecks: function (origin, path, enabled) {
            return OctoPrint.postJson(base() + "files/" + encodeURIComponent(origin) + "/" + enc(path),
                {checks_enabled: !!enabled});
        },

        calibrationBoard: function () {
            return OctoPrint.get(base() + "calibration/board");
        },
        calibration: function (camera) {
            return OctoPrint.get(base() + "calibration/" + encodeURIComponent(camera));
        },
        captureCalibrationFrame: function (camera) {
            return OctoPrint.postJson(base() + "calibration/" + encodeURIComponent(camera) + "/capture", {});
        },
        deleteCalibrationFrame: function (camera, index) {
            return OctoPrint.delete(base() + "calibration/" + encodeURIComponent(camera) + "/frames/" + encodeURIComponent(index));
        },
        resetCalibration: function (camera) {
            return OctoPrint.delete(base() + "calibration/" + encodeURIComponent(camera));
        },
        computeCalibration: function (camera) {
            return OctoPrint.postJson(base() + "calibration/" + encodeURIComponent(camera) + "/compute", {});
        },
        saveCalibration: function (camera) {
            return OctoPrint.postJson(base() + "calibration/" + encodeURIComponent(camera) + "/save", {});
        }
    };
})(window);
