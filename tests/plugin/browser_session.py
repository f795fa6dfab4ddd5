"""Drives Debian's Chromium (never a downloaded browser) through Playwright against a running OctoPrint.

Used by the browser tests and by anyone who wants fresh screenshots of the UI: with
``PRINTWATCH_SCREENSHOTS=docs/img`` the browser tests rewrite the README's ``docs/img/ui_*.png``;
without it they go to a folder under the system's temporary directory, so running the suite never
changes the checkout.
"""
from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
SCREENSHOTS = Path(os.environ.get("PRINTWATCH_SCREENSHOTS") or Path(tempfile.gettempdir()) / "printwatch-screenshots")


def chromium_available() -> bool:
    if not Path(CHROMIUM).exists():
        return False
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass
class PageLog:
    """What the page said on its console; JS errors in our code fail the tests."""

    messages: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    def printwatch_errors(self) -> list[str]:
        """Console errors and uncaught exceptions that mention PrintWatch code."""
        return [e for e in self.errors if "printwatch" in e.lower() or "uplot" in e.lower()]


@contextlib.contextmanager
def browser() -> Iterator:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield chromium
        finally:
            chromium.close()


def new_page(chromium, width: int = 1280, height: int = 1000):
    """A page with its console captured in ``page.printwatch_log`` (a PageLog)."""
    page = chromium.new_page(viewport={"width": width, "height": height})
    log = PageLog()

    def on_console(message):
        text = f"{message.type}: {message.text}"
        log.messages.append(text)
        if message.type == "error":
            log.errors.append(text)

    page.on("console", on_console)
    page.on("pageerror", lambda error: log.errors.append(f"pageerror: {error}"))
    page.printwatch_log = log
    return page


def login(page, base_url: str, user: str, password: str, timeout_ms: float = 60000) -> None:
    """Log in through OctoPrint's login page and wait until the UI has started."""
    page.goto(base_url + "/", wait_until="domcontentloaded", timeout=timeout_ms)
    page.wait_for_selector("#login-user", timeout=timeout_ms)
    page.fill("#login-user", user)
    page.fill("#login-password", password)
    page.click("#login-button")
    wait_for_ui(page, timeout_ms)
    dismiss_wizard(page)


def dismiss_wizard(page, appear_ms: float = 3000, timeout_ms: float = 15000) -> None:
    """Finish OctoPrint's setup wizard if a bundled plugin opens it (File Check does after uploads).

    The wizard opens a moment after start-up, so wait ``appear_ms`` for it first.
    """
    try:
        page.wait_for_selector("#wizard_dialog", state="visible", timeout=appear_ms)
    except Exception:  # noqa: BLE001 - no wizard: nothing to do
        return
    for _ in range(20):
        if not page.locator("#wizard_dialog").is_visible():
            return
        finish = page.locator("#wizard_dialog .button-finish")
        if finish.is_visible():
            finish.click()
        else:
            page.locator("#wizard_dialog .button-next").click()
        page.wait_for_timeout(300)
    page.wait_for_selector("#wizard_dialog", state="hidden", timeout=timeout_ms)


def wait_for_ui(page, timeout_ms: float = 60000) -> None:
    """Wait until OctoPrint's view models are bound (the loading overlay is gone)."""
    page.wait_for_selector("#tabs", timeout=timeout_ms)
    page.wait_for_function(
        "() => window.OctoPrint && OctoPrint.coreui && OctoPrint.coreui.startedUp === true",
        timeout=timeout_ms,
    )


def reload(page, timeout_ms: float = 60000) -> None:
    """Reload the page and wait until OctoPrint's UI has started again."""
    page.reload(wait_until="domcontentloaded", timeout=timeout_ms)
    wait_for_ui(page, timeout_ms)
    dismiss_wizard(page)


def open_printwatch_tab(page, timeout_ms: float = 30000) -> None:
    page.click('#tabs a[href="#tab_plugin_printwatch"]')
    page.wait_for_selector("#tab_plugin_printwatch", state="visible", timeout=timeout_ms)


def open_printwatch_settings(page, timeout_ms: float = 30000) -> None:
    page.click("#navbar_show_settings")
    page.wait_for_selector("#settings_dialog", state="visible", timeout=timeout_ms)
    page.click('#settings_dialog_menu a[href="#settings_plugin_printwatch"]')
    page.wait_for_selector("#settings_plugin_printwatch", state="visible", timeout=timeout_ms)
    # Bootstrap fades the dialog in: "visible" comes first, and a screenshot then shows the page through it
    page.wait_for_function("getComputedStyle(document.querySelector('#settings_dialog')).opacity === '1'",
                           timeout=timeout_ms)


def save_settings(page, timeout_ms: float = 30000) -> None:
    page.click("#settings_dialog [data-test-id=settings-save]")
    page.wait_for_selector("#settings_dialog", state="hidden", timeout=timeout_ms)


def screenshot(page, name: str, selector: str | None = None) -> Path:
    """Save ``ui_<name>.png`` in ``SCREENSHOTS`` (a whole page, or one element) and return its path."""
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    path = SCREENSHOTS / f"ui_{name}.png"
    tmp = path.with_suffix(".tmp.png")
    if selector:
        page.locator(selector).screenshot(path=str(tmp))
    else:
        page.screenshot(path=str(tmp), full_page=False)
    shutil.move(tmp, path)
    return path
