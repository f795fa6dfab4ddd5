"""``printwatch demo``: a real OctoPrint with PrintWatch watching a simulated print, start to finish.

What it does, in order:

1. builds the print simulator's rig (three stations of relaxed stereo pairs, or the first N
   of its cameras) and writes each camera's calibration - the rig's *calibrated* estimate,
   calibration error included - into PrintWatch's settings, as the calibration wizard saves it;
2. starts ``octoprint serve`` (virtual printer, users with API keys, offline) and the simulated
   webcams, which render the print's actual progress by following OctoPrint's job;
3. uploads the part's sliced G-code through OctoPrint's API (PrintWatch's upload hook injects
   the checks), waits for the expected views, sends ``M220 S1000`` and starts the print;
4. reports every check as it happens, then the outcome: a failure scenario must pause at the
   first check where the failure is big enough to see (the simulator's own truth), a normal
   print must complete with no pause.

Interactive runs keep OctoPrint up after the print until Ctrl-C so the visitor can look;
``headless`` runs stop everything and return the outcome.
"""
from __future__ import annotations

import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Sequence

from ..core.errors import PrintWatchError

API = "/plugin/printwatch"
#: States of OctoPrint's job in which the print is still going.
RUNNING_STATES = ("Printing", "Starting", "Pausing", "Cancelling", "Resuming", "Finishing")


class DemoError(PrintWatchError):
    """The demo cannot run as asked (bad option, port taken, OctoPrint missing)."""


@dataclass
class DemoOptions:
    part: str = "twisted_vase"
    failure: str = "runout"           # a simulator scenario kind, or "none"
    onset_layer: int | None = None    # None: part-way, a few layers after a check
    cameras: int = 6                  # the first N cameras of the three-station rig
    every_layers: int | None = None   # None: about eight checks over the part
    headless: bool = False
    port: int | None = None           # None: 5000 when free, else any free port
    basedir: Path | None = None       # None: a temporary folder, removed at the end
    seed: int = 7                     # rig placement, calibration error, look of the scene
    speed_percent: int = 1000         # M220: the virtual printer ten times faster
    timeout_s: float = 900.0          # headless: give up on a print that does not end


@dataclass
class CheckLine:
    layer: int
    verdict: str
    worst_shape_pct: float | None
    worst_size_pct: float | None
    seconds: float | None
    hold_seconds: float | None
    reasons: list = field(default_factory=list)


@dataclass
class DemoResult:
    """What happened, and whether that is what a working PrintWatch does."""

    failure: str
    onset_layer: int | None
    planned_layers: list[int]
    expected_pause_layer: int | None   # the first check where the failure is due (None: normal print)
    final_state: str                   # OctoPrint's job state at the end ("Operational", "Paused", ...)
    paused_layer: int | None           # the layer of the first failing check, if any
    reason: str | None
    checks: list[CheckLine]
    print_seconds: float

    @property
    def outcome(self) -> str:
        """detected | late | missed | false pause | completed | checks missing | not finished."""
        failed_before_onset = self.paused_layer is not None and (
            self.onset_layer is None or self.paused_layer < self.onset_layer)
        if failed_before_onset:
            return "false pause"
        if self.failure == "none":
            if not self.final_state.startswith("Operational"):
                return "not finished"
            # a print that ends with checks left out was not watched to the end
            return "completed" if len(self.checks) == len(self.planned_layers) else "checks missing"
        if self.paused_layer is None:
            return "missed"
        if self.expected_pause_layer is not None and self.paused_layer > self.expected_pause_layer:
            return "late"
        return "detected"

    @property
    def ok(self) -> bool:
        return self.outcome in ("detected", "completed")


# ---------------------------------------------------------------------------- set-up
def library_parts() -> list[str]:
    from ..simulator.parts import PARTS_DIR

    return sorted(p.stem for p in PARTS_DIR.glob("*.gcode") if (PARTS_DIR / f"{p.stem}.stl").exists())


def validate(options: DemoOptions) -> None:
    from ..simulator.scenario import SCENARIOS

    if options.failure == "normal":
        options.failure = "none"
    parts = library_parts()
    if options.part not in parts:
        raise DemoError(f"--part {options.part!r}: not a library part; choose from {', '.join(parts)}")
    if options.failure != "none" and (options.failure not in SCENARIOS or options.failure == "normal"):
        kinds = [k for k in SCENARIOS if k != "normal"] + ["none"]
        raise DemoError(f"--failure {options.failure!r}: choose from {', '.join(kinds)}")
    if not 1 <= options.cameras <= 6:
        raise DemoError(f"--cameras {options.cameras}: the demo rig has 1 to 6 cameras")
    if options.every_layers is not None and options.every_layers < 1:
        raise DemoError(f"--every {options.every_layers}: must be 1 or more layers")
    if options.onset_layer is not None and options.onset_layer < 2:
        raise DemoError(f"--onset-layer {options.onset_layer}: must be 2 or more (layer 1 is the first layer)")
    try:
        import octoprint  # noqa: F401
        import requests  # noqa: F401
        import yaml  # noqa: F401
    except ImportError:
        raise DemoError("the demo needs OctoPrint: pip install 'octoprint-printwatch[octoprint]' "
                        "(or run scripts/demo.sh, which sets everything up)") from None


def port_is_free(port: int) -> bool:
    with socket.socket() as sock:
        try:
            sock.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def choose_port(requested: int | None) -> int:
    from .octoprint_server import free_port

    if requested is not None:
        if not 1 <= requested <= 65535:
            raise DemoError(f"--port {requested}: not a TCP port")
        if not port_is_free(requested):
            raise DemoError(f"--port {requested}: something already listens on 127.0.0.1:{requested}")
        return requested
    return 5000 if port_is_free(5000) else free_port()


def default_every(n_layers: int) -> int:
    """About eight checks over the part (a multiple of 5 layers), at least 20 layers (4 mm) apart so a
    failure starting just after one check is plainly visible at the next."""
    return max(20, int(round(n_layers / 8 / 5.0)) * 5)


def default_onset(n_layers: int, every: int) -> int:
    """The layer just after the check nearest below 45 % of the height: checks pass, then the next one sees it."""
    anchor = max(every, int(n_layers * 0.45) // every * every)
    return min(n_layers, anchor + 1)


@dataclass
class DemoRig:
    cameras: list[str]                 # simulator camera names, also PrintWatch's camera names
    pairs: list[tuple[str, str]]
    calibrations: dict                 # name -> Camera.to_dict() of the calibrated estimate
    n_layers: int
    simulator: object                  # PrintSimulator of the scenario, for its truth


def build_rig(options: DemoOptions) -> DemoRig:
    from ..simulator.rig import make_rig
    from ..simulator.scenario import Scenario
    from ..simulator.scene import PrintSimulator

    rig = make_rig("stations3", seed=options.seed)
    names = rig.names[: options.cameras]
    kind = "normal" if options.failure == "none" else options.failure
    sim = PrintSimulator(options.part, rig=rig, scenario=Scenario(kind, onset_layer=options.onset_layer),
                         seed=options.seed)
    pairs = [(l, r) for l, r in rig.pairs if l in names and r in names]
    return DemoRig(names, pairs, {n: rig.calibrated(n).to_dict() for n in names}, sim.n_layers, sim)


def printwatch_settings(rig: DemoRig, webcam_port: int, every: int) -> dict:
    def label(name: str) -> str:  # cam1L -> "Station 2 left"
        station, side = name[3:-1], name[-1]
        return f"Station {int(station) + 1} {'left' if side == 'L' else 'right'}"

    return {
        "every_layers": every,
        "lift_mm": 10.0,
        # the simulated webcams render on demand (one frame at a time): give six of them time
        "camera_timeout_s": 20.0,
        "use_octoprint_webcams": False,
        "cameras": [{"name": n, "label": label(n), "type": "url", "url": f"http://127.0.0.1:{webcam_port}/{n}.jpg"}
                    for n in rig.cameras],
        "calibrations": rig.calibrations,
        "pairs": [list(p) for p in rig.pairs],
        "size_check": bool(rig.pairs),
    }


def write_config(server, rig: DemoRig, webcam_port: int) -> None:
    """OctoPrint's config: PrintWatch's settings, the visitor logged in automatically from this machine,
    and OctoPrint's own webcam showing the first simulated camera (Control tab)."""
    import yaml

    server.write_config()
    path = server.basedir / "config.yaml"
    config = yaml.safe_load(path.read_text())
    config["accessControl"] = {"autologinLocal": True, "autologinAs": "admin",
                               "localNetworks": ["127.0.0.0/8", "::1/128"]}
    first = f"http://127.0.0.1:{webcam_port}/{rig.cameras[0]}.jpg"
    config["plugins"]["classicwebcam"] = {"snapshot": first, "stream": first, "snapshotTimeout": 20,
                                          "_config_version": 1}
    path.write_text(yaml.safe_dump(config))


def start_webcams(port: int, octoprint_url: str, apikey: str, options: DemoOptions, log: Path) -> subprocess.Popen:
    kind = "normal" if options.failure == "none" else options.failure
    return launch_webcam_server(port, octoprint_url, apikey, part=options.part, rig="stations3", seed=options.seed,
                                scenario=kind, onset_layer=options.onset_layer, log=log)


def launch_webcam_server(port: int, octoprint_url: str, apikey: str, *, part: str, rig: str, seed: int,
                         scenario: str, onset_layer: int | None = None, dead: Sequence[str] = (),
                         log: Path | None = None, timeout_s: float = 60.0) -> subprocess.Popen:
    """Start the simulated webcams (``demo.webcam_server``) in a subprocess and wait until they answer.

    Used by the demo and by the integration tests' stack; raises :class:`DemoError` (one line, naming
    the log) when the server exits or does not answer within ``timeout_s``.
    """
    import requests

    args = [sys.executable, "-m", "octoprint_printwatch.demo.webcam_server", "--port", str(port),
            "--octoprint", octoprint_url, "--apikey", apikey, "--part", part, "--rig", rig,
            "--seed", str(seed), "--scenario", scenario]
    if onset_layer is not None:
        args += ["--onset-layer", str(onset_layer)]
    for name in dead:
        args += ["--dead", name]
    out = open(log, "ab") if log else subprocess.DEVNULL
    process = subprocess.Popen(args, stdout=out, stderr=subprocess.STDOUT)
    where = f"; see {log}" if log else ""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise DemoError(f"the simulated webcams exited with status {process.returncode}{where}")
        try:
            requests.get(f"http://127.0.0.1:{port}/served", timeout=1)
            return process
        except requests.RequestException:
            time.sleep(0.3)
    stop_process(process)
    raise DemoError(f"the simulated webcams did not answer within {timeout_s:g} s{where}")


def stop_process(process: subprocess.Popen | None) -> None:
    if process is None or process.poll() is not None:
        return
    process.terminate()
    try:
        process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait(timeout=10)


# ---------------------------------------------------------------------------- the print
def expected_pause_layer(rig: DemoRig, planned: list[tuple[int, float]]) -> int | None:
    """The first planned check at which the simulator says a working detector must flag the failure."""
    for layer, z in planned:
        if rig.simulator.truth(z)["should_flag"]:
            return layer
    return None


def wait_prepared(server, path: str, timeout: float, say: Callable[[str], None]) -> None:
    """Wait (bounded) for the expected views, so the first check is not held by rendering."""
    deadline = time.monotonic() + timeout
    last = None
    while time.monotonic() < deadline:
        state = (server.get(f"{API}/files/local/{path}").get("preparation") or {}).get("state")
        if state != last and state in ("queued", "rendering"):
            say("rendering the expected views for every camera and check height ...")
        last = state
        if state in ("ready", "failed", "none", None):
            return
        time.sleep(0.5)
    say("the expected views are still rendering; starting anyway (the first check waits for them)")


def check_line(check: dict) -> CheckLine:
    shapes = [v for v in (check.get("shape_error_pct") or {}).values() if v is not None]
    sizes = [v.get("error_pct") for v in (check.get("size") or {}).values() if v.get("error_pct") is not None]
    return CheckLine(int(check["layer"]), str(check["verdict"]), max(shapes) if shapes else None,
                     max(sizes) if sizes else None, check.get("seconds"), check.get("hold_seconds"),
                     list(check.get("reasons") or []))


def describe(line: CheckLine) -> str:
    parts = [f"check at layer {line.layer}: {line.verdict.upper()}"]
    if line.worst_shape_pct is not None:
        parts.append(f"worst shape error {line.worst_shape_pct:.1f} %")
    if line.worst_size_pct is not None:
        parts.append(f"worst size error {line.worst_size_pct:.1f} %")
    if line.hold_seconds is not None:
        parts.append(f"job held {line.hold_seconds:.1f} s")
    text = ", ".join(parts)
    if line.verdict != "ok" and line.reasons:
        text += f" - {line.reasons[0]}"
    return text


def watch_print(server, timeout: float, say: Callable[[str], None]) -> tuple[str, list[dict]]:
    """Report checks as they land until the job stops printing; (final job state, checks of the print)."""
    seen = 0
    deadline = time.monotonic() + timeout
    print_id = None
    started = False  # "Operational" before the job got going is not the end of the print
    while True:
        state = server.job()["state"]
        status = server.get(f"{API}/status")
        print_id = status.get("print_id") or print_id
        started = started or print_id is not None or state.startswith(RUNNING_STATES + ("Paused",))
        checks = server.get(f"{API}/prints/{print_id}")["checks"] if print_id else []
        for check in checks[seen:]:
            say("  " + describe(check_line(check)))
        seen = max(seen, len(checks))
        if started and not state.startswith(RUNNING_STATES):
            if print_id is None:
                prints = server.get(f"{API}/prints").get("prints") or []
                print_id = prints[0]["id"] if prints else None
            # the plugin lifts the hold before it stores the verdict and closes the print after the
            # check it is storing: a print whose result is no longer "running" holds every check
            final = server.get(f"{API}/prints/{print_id}") if print_id else {"checks": checks}
            settle = time.monotonic() + 30.0
            while final.get("result") == "running" and state != "Paused" and time.monotonic() < settle:
                time.sleep(0.3)
                final = server.get(f"{API}/prints/{print_id}")
            final = final["checks"]
            for check in final[seen:]:
                say("  " + describe(check_line(check)))
            return state, final
        if time.monotonic() > deadline:
            raise DemoError(f"the print did not end within {timeout:.0f} s (OctoPrint says {state!r})")
        time.sleep(0.5)


def summary_text(result: DemoResult) -> str:
    holds = [c.hold_seconds for c in result.checks if c.hold_seconds is not None]
    vision = [c.seconds for c in result.checks if c.seconds is not None]
    verdicts = {}
    for c in result.checks:
        verdicts[c.verdict] = verdicts.get(c.verdict, 0) + 1
    scenario = "normal print" if result.failure == "none" else f"{result.failure} from layer {result.onset_layer}"
    lines = [
        "PrintWatch demo summary",
        f"  scenario        : {scenario}",
        f"  checks planned  : {len(result.planned_layers)} (layers {', '.join(map(str, result.planned_layers))})",
        f"  checks run      : {len(result.checks)} ("
        + ", ".join(f"{n} {v}" for v, n in sorted(verdicts.items())) + ")",
        f"  printer state   : {result.final_state} after {result.print_seconds:.0f} s",
    ]
    if result.paused_layer is not None:
        lines.append(f"  paused at       : the check at layer {result.paused_layer}"
                     + (f" (expected: layer {result.expected_pause_layer})" if result.expected_pause_layer else ""))
        if result.reason:
            reason = result.reason if len(result.reason) <= 300 else result.reason[:297] + "..."
            lines.append(f"  reason          : {reason}")
    elif result.expected_pause_layer is not None:
        lines.append(f"  paused at       : never (expected: the check at layer {result.expected_pause_layer})")
    if holds:
        lines.append(f"  time per check  : job held median {statistics.median(holds):.1f} s, max {max(holds):.1f} s"
                     + (f"; vision median {statistics.median(vision):.1f} s" if vision else ""))
    lines.append(f"  outcome         : {result.outcome.upper()}"
                 + ("" if result.ok else " - this is not what a working PrintWatch does"))
    return "\n".join(lines)


def run_demo(options: DemoOptions, say: Callable[[str], None] = print,
             wait_for_visitor: Callable[[], None] | None = None) -> DemoResult:
    """Run the demo; returns the result. Interactive runs then block until Ctrl-C (KeyboardInterrupt)."""
    from .octoprint_server import ADMIN_KEY, ADMIN_PASSWORD, ADMIN_USER, OctoPrintServer, free_port

    validate(options)
    port = choose_port(options.port)
    n_layers = build_rig(replace(options, failure="none", onset_layer=None)).n_layers
    if options.onset_layer is not None and options.onset_layer > n_layers:
        raise DemoError(f"--onset-layer {options.onset_layer}: {options.part} has only {n_layers} layers")
    every = options.every_layers or default_every(n_layers)
    if options.failure != "none" and options.onset_layer is None:
        options.onset_layer = default_onset(n_layers, every)
    rig = build_rig(options)
    if options.failure != "none":
        # the injector checks every N layers and always the last one
        likely = sorted(set(range(every, rig.n_layers + 1, every)) | {rig.n_layers})
        if expected_pause_layer(rig, [(layer, rig.simulator.layer_z(layer)) for layer in likely]) is None:
            raise DemoError(f"--onset-layer {options.onset_layer}: a {options.failure} starting there is not "
                            f"visible by the last check (layer {rig.n_layers}); choose an earlier layer")

    temporary = options.basedir is None
    basedir = Path(tempfile.mkdtemp(prefix="printwatch-demo-")) if temporary else Path(options.basedir)
    if not temporary and basedir.exists() and any(basedir.iterdir()):
        raise DemoError(f"--basedir {basedir}: not empty; give a new or empty folder (the demo writes a fresh "
                        "OctoPrint configuration there)")
    import requests

    webcams = None
    server = None
    keep = not temporary
    try:
        webcam_port = free_port()
        server = OctoPrintServer(basedir, printwatch_settings(rig, webcam_port, every), port=port)
        write_config(server, rig, webcam_port)
        say(f"PrintWatch demo: {options.part}, {len(rig.cameras)} simulated camera(s) "
            f"({len(rig.pairs)} stereo pair(s)), "
            + ("a normal print" if options.failure == "none" else
               f"{options.failure} injected at layer {options.onset_layer} of {rig.n_layers}"))
        say(f"starting OctoPrint in {basedir} (about half a minute) ...")
        server.start(timeout=180)
        webcams = start_webcams(webcam_port, server.url, ADMIN_KEY, options, basedir / "webcams.log")
        server.wait_operational(timeout=120)
        say("")
        say(f"  OctoPrint is at {server.url}  (login: {ADMIN_USER} / {ADMIN_PASSWORD}; "
            "browsers on this machine are logged in automatically)")
        say("  open the PrintWatch tab to watch the checks")
        say("")
        result = demonstrate(server, rig, options, every, say, wait_for_visitor)
        say("")
        say(summary_text(result))
        if not options.headless:
            say("")
            say(f"OctoPrint stays up at {server.url}: look at the PrintWatch tab (chart, overlays, history). "
                "Ctrl-C stops everything.")
            try:
                while server.process is not None and server.process.poll() is None:
                    time.sleep(1.0)
            except KeyboardInterrupt:
                pass
            say("stopping OctoPrint and the simulated webcams ...")
        return result
    except (requests.RequestException, RuntimeError, TimeoutError, DemoError) as exc:
        keep = True  # the logs say why
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise DemoError(f"{detail} (OctoPrint's files and logs are kept in {basedir})") from None
    finally:
        stop_process(webcams)
        if server is not None:
            server.stop()
        if not keep:
            shutil.rmtree(basedir, ignore_errors=True)


def demonstrate(server, rig: DemoRig, options: DemoOptions, every: int, say: Callable[[str], None],
                wait_for_visitor: Callable[[], None] | None) -> DemoResult:
    """Upload (PrintWatch injects), wait for the expected views, print fast, watch; the result."""
    gcode = Path(__file__).resolve().parents[1] / "data" / "parts" / f"{options.part}.gcode"
    uploaded = server.upload(gcode)
    path = uploaded["files"]["local"]["path"]
    planned = [(int(c["layer"]), float(c["z"])) for c in server.get(f"{API}/files/local/{path}")["checks"]]
    if not planned:
        raise DemoError(f"PrintWatch injected no checks into {gcode.name}")
    say(f"uploaded {gcode.name}: PrintWatch injected {len(planned)} checks "
        f"(every {every} layers: {', '.join(str(l) for l, _ in planned)})")
    expected = expected_pause_layer(rig, planned) if options.failure != "none" else None
    wait_prepared(server, path, timeout=300, say=say)
    if wait_for_visitor is not None:
        wait_for_visitor()
    server.post("/api/printer/command", {"commands": [f"M220 S{int(options.speed_percent)}"]}).raise_for_status()
    server.post(f"/api/files/local/{path}", {"command": "select", "print": True}).raise_for_status()
    say(f"printing at {options.speed_percent} % speed (M220 S{options.speed_percent}) ...")
    started = time.monotonic()
    final_state, checks = watch_print(server, options.timeout_s, say)
    lines = [check_line(c) for c in checks]
    failing = next((c for c in lines if c.verdict == "fail"), None)
    reason = None
    if failing is not None:
        last_failure = server.get(f"{API}/status").get("last_failure") or {}
        reason = last_failure.get("reason") or (failing.reasons[0] if failing.reasons else None)
    return DemoResult(options.failure, options.onset_layer, [l for l, _ in planned], expected, final_state,
                      failing.layer if failing else None, reason, lines, time.monotonic() - started)
