"""The browser tests' one way to drive Debian's chromium (``make test-browser`` installs it):
headless options, waiting for a page, and opening local pages offline with every request recorded."""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

CHROMIUM = os.environ.get("LORISNB_CHROMIUM", "/usr/bin/chromium")
CHROMEDRIVER = os.environ.get("LORISNB_CHROMEDRIVER", "/usr/bin/chromedriver")
#: Schemes a page opened offline may request: anything else would leave the machine.
LOCAL = ("file:", "data:", "about:", "chrome", "blob:")


def need_chromium() -> None:
    """Fail (not skip: CI must run them) when chromium or its driver is missing."""
    if not (Path(CHROMIUM).exists() and Path(CHROMEDRIVER).exists()):
        pytest.fail(f"{CHROMIUM} / {CHROMEDRIVER} missing: run `make test-browser` (installs Debian's chromium)")


def chromium(profile: Path, size: str = "1300,1000", offline: bool = False, record: bool = False) -> Any:
    """A headless chromium with its profile in ``profile``; ``offline``: no proxy reachable (every
    request that is not local fails); ``record``: Chrome's performance log kept (the requests)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    need_chromium()
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync", "--disable-quic",
                f"--window-size={size}", f"--user-data-dir={profile}"):  # fmt: skip
        opts.add_argument(arg)
    if offline:
        opts.add_argument("--proxy-server=127.0.0.1:9")
    if record:
        opts.set_capability("goog:loggingPrefs", {"performance": "ALL"})
    return webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)


def wait(cond: Callable[[], Any], timeout: float, what: str, interval: float = 0.25) -> Any:
    """``cond()``'s first true value within ``timeout`` seconds (an exception counts as not yet)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            got = cond()
        except Exception:  # the page is still changing under us
            got = None
        if got:
            return got
        time.sleep(interval)
    raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")


class OfflinePages:
    """Local pages opened in a chromium with every http(s) and ws(s) request blocked, each request
    recorded: :meth:`open` checks that the page loads and every image on it shows."""

    def __init__(self, driver: Any) -> None:
        self.driver = driver
        self.requested: list[str] = []
        driver.execute_cdp_cmd("Network.enable", {})
        driver.execute_cdp_cmd("Network.setBlockedURLs", {"urls": ["http://*", "https://*", "ws://*", "wss://*"]})

    def open(self, page: Path, scroll: bool = False, settle_s: float = 0.5) -> None:
        """Open ``page`` (``scroll``: to its end, so lazy images load), record its requests, and
        assert that every image loaded."""
        d = self.driver
        d.get(page.as_uri())
        wait(lambda: d.execute_script("return document.readyState") == "complete", 30, f"{page.name} to load")
        if scroll:
            d.execute_script("window.scrollTo(0, document.body.scrollHeight)")
        time.sleep(settle_s)
        for entry in d.get_log("performance"):
            msg = json.loads(entry["message"])["message"]
            if msg["method"] == "Network.requestWillBeSent":
                self.requested.append(msg["params"]["request"]["url"])
        broken = d.execute_script(
            "return Array.from(document.images).filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.src)"
        )
        assert broken == [], f"{page.name}: images that did not load: {broken}"

    def outside(self) -> list[str]:
        """The requests that would have left the machine."""
        return [u for u in self.requested if not u.startswith(LOCAL)]


@contextmanager
def offline_pages(profile: Path, size: str = "1300,1000") -> Iterator[OfflinePages]:
    """:class:`OfflinePages` in a chromium of its own, closed after."""
    driver = chromium(profile, size, offline=True, record=True)
    try:
        yield OfflinePages(driver)
    finally:
        driver.quit()
