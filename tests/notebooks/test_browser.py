"""The notebooks in a real browser, as a student uses them: JupyterLab on a loopback port with a
token, Debian's Chromium driven by selenium through its own executable (no browser download).

For every notebook: open it (it must not be marked modified), run all cells, and assert no error
output and no figure shown twice in a cell. For each interactive explorer: the first values shown
equal the notebook's parameters, and a slider drag, an arrow key and (threshold explorer) a
dropdown change each change the figure, which is never blank (its pixels are checked).
Screenshots of each explorer before and after each input land in ``results/browser/``.

Run with ``make test-browser`` (installs Chromium with apt where missing).
"""

from __future__ import annotations

import io
import json
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from browser import chromium, need_chromium, offline_pages, wait
from helpers import temp_dir_left_as_found

from lorisnb.core.trajectory.frames import PAPER_EPS
from lorisnb.tools.report.build import DEFAULT_NOTEBOOKS, notebook_dir

pytestmark = [pytest.mark.browser, pytest.mark.slow]

PANEL = "document.querySelector('.jp-NotebookPanel:not(.lm-mod-hidden)')"  # the notebook in front
CURRENT_TAB = "(document.querySelector('#jp-main-dock-panel .lm-TabBar-tab.lm-mod-current .lm-TabBar-tabLabel') || {}).textContent || ''"
SHOTS = Path(__file__).resolve().parents[2] / "results" / "browser"
TOKEN = "lorisnb-browser-test"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module", autouse=True)
def _temp_dir():
    with temp_dir_left_as_found():
        yield


@pytest.fixture(scope="module")
def lab(tmp_path_factory, data):
    """A JupyterLab server on 127.0.0.1 over a copy of the notebooks; stopped at the end. Its temporary
    folder (TMPDIR: the server's, its kernels', the notebooks' output folders, which they make there
    outside a checkout) is ``tmp/`` in the lab's folder, not the machine's."""
    need_chromium()
    root = tmp_path_factory.mktemp("lab")
    (root / "tmp").mkdir()
    for p in notebook_dir().glob("*.ipynb"):
        shutil.copy(p, root / p.name)
    settings = root / ".settings" / "@jupyterlab" / "notebook-extension"
    settings.mkdir(parents=True)
    (settings / "tracker.jupyterlab-settings").write_text(json.dumps({"windowingMode": "none"}))
    notify = root / ".settings" / "@jupyterlab" / "apputils-extension"
    notify.mkdir(parents=True)
    (notify / "notification.jupyterlab-settings").write_text(
        json.dumps({"fetchNews": "false", "checkForUpdates": False})
    )
    port = _free_port()
    env = dict(os.environ, LORISNB_DATA=str(data.root), JUPYTERLAB_SETTINGS_DIR=str(root / ".settings"),
               MPLBACKEND="module://matplotlib_inline.backend_inline", TMPDIR=str(root / "tmp"))  # fmt: skip
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    log = open(root / "lab.log", "w")
    proc = subprocess.Popen(
        [sys.executable, "-m", "jupyter", "lab", "--no-browser", "--ServerApp.ip=127.0.0.1", f"--ServerApp.port={port}",
         f"--IdentityProvider.token={TOKEN}", f"--ServerApp.root_dir={root}", "--ServerApp.open_browser=False",
         f"--LabApp.workspaces_dir={root / '.workspaces'}",
         "--LabApp.news_url=", "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate"]
        + (["--allow-root"] if os.geteuid() == 0 else []),
        cwd=root, env=env, stdout=log, stderr=subprocess.STDOUT,
    )  # fmt: skip
    url = f"http://127.0.0.1:{port}"
    for _ in range(120):
        if proc.poll() is not None:
            break
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=1):
                break
        except OSError:
            time.sleep(0.5)
    else:
        proc.terminate()
        pytest.fail("JupyterLab did not start: " + (root / "lab.log").read_text()[-2000:])
    yield url, root
    proc.terminate()
    try:
        proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
    log.close()


@pytest.fixture(scope="module")
def browser(lab):
    driver = chromium(lab[1] / ".chromium", size="1500,1100")
    driver.set_script_timeout(30)
    yield driver
    driver.quit()


def _shot(el, name: str) -> bytes:
    SHOTS.mkdir(parents=True, exist_ok=True)
    png = el.screenshot_as_png
    (SHOTS / f"{name}.png").write_bytes(png)
    return png


def _not_blank(png: bytes) -> bool:
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(png)).convert("L"), float)
    return img.shape[0] > 120 and img.shape[1] > 200 and (img < 235).mean() > 0.03 and img.std() > 25


def _open_and_run(driver, url: str, name: str, timeout: float) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    driver.get(f"{url}/lab/tree/{name}.ipynb?token={TOKEN}")
    # the notebook in front (its tab: headless Chromium 156 no longer gets JupyterLab's document.title)
    wait(lambda: driver.execute_script(f"const p = {PANEL}; return p && p.querySelector('.jp-Cell') && "
                                        f"{CURRENT_TAB}.startsWith('{name}.ipynb')"), 60, f"{name} to open")  # fmt: skip
    wait(lambda: "Idle" in driver.execute_script(
        "const s = document.querySelector('.jp-Notebook-ExecutionIndicator, .jp-Toolbar-kernelStatus');"
        "return s ? (s.getAttribute('title') || s.textContent || '') + ' Idle' : '';"), 60, "the kernel")  # fmt: skip
    time.sleep(1.0)
    tab = driver.find_element(By.CSS_SELECTOR, ".lm-DockPanel-tabBar .lm-TabBar-tab.lm-mod-current")
    assert "jp-mod-dirty" not in tab.get_attribute("class"), f"{name} is marked modified as soon as it opens"

    def run_all() -> None:
        _no_dialog(driver, name)
        driver.find_element(By.XPATH, "//div[contains(@class,'lm-MenuBar-itemLabel') and text()='Run']").click()
        wait(lambda: driver.find_element(By.XPATH, "//div[contains(@class,'lm-Menu-itemLabel') and text()='Run All Cells']"),
              10, "the Run menu").click()  # fmt: skip

    def prompts() -> list[str]:
        return [p.strip() for p in driver.execute_script(
            f"return Array.from({PANEL}.querySelectorAll('.jp-CodeCell .jp-InputPrompt')).map(e => e.textContent)"
        )]  # fmt: skip

    def done():
        got = prompts()
        return got and all(p not in ("[ ]:", "[*]:", "") for p in got)

    def stalled() -> bool:  # cells left unrun, none running or queued, no error shown: the run was dropped
        got = prompts()
        return "[ ]:" in got and "[*]:" not in got and not _errors(driver)

    run_all()
    started = time.monotonic()
    while time.monotonic() - started < 20 and all(p in ("[ ]:", "") for p in prompts()):
        time.sleep(0.5)
    if all(p in ("[ ]:", "") for p in prompts()):  # the menu click was lost (nothing queued): once more
        driver.find_element(By.TAG_NAME, "body").send_keys(Keys.ESCAPE)
        run_all()
    deadline, still, again = time.monotonic() + timeout, None, 2
    while not done():
        if "[*]:" not in prompts() and _errors(driver):  # stopped at an error: the caller reports it
            return
        _no_dialog(driver, name)
        now = time.monotonic()
        still = (still or now) if stalled() else None
        if still is not None and now - still > 15 and again:  # dropped for 15 s (not slow): run all once more
            driver.find_element(By.TAG_NAME, "body").send_keys(Keys.ESCAPE)
            run_all()
            still, again = None, again - 1
        if now > deadline:  # say which cells did not run, and keep a picture of it
            _shot(driver.find_element(By.CSS_SELECTOR, ".jp-NotebookPanel:not(.lm-mod-hidden)"), f"{name}-stuck")
            raise AssertionError(f"timed out after {timeout:.0f} s waiting for every cell of {name} to run; "
                                 f"cell prompts: {prompts()}")  # fmt: skip
        time.sleep(1.0)


def _no_dialog(driver, name: str) -> None:
    """Fail with what a JupyterLab dialog says (a kernel that died, say) instead of clicking into
    it; the dialog is pictured (results/browser/NAME-dialog.png) and closed (Escape)."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    text = driver.execute_script("const d = document.querySelector('.jp-Dialog'); return d ? d.innerText : ''")
    if text:
        _shot(driver.find_element(By.CSS_SELECTOR, ".jp-Dialog"), f"{name}-dialog")
        driver.switch_to.active_element.send_keys(Keys.ESCAPE)
        raise AssertionError(f"{name}: JupyterLab showed a dialog: {' '.join(text.split())[:500]}")


def _errors(driver) -> list[str]:
    return driver.execute_script(
        f"return Array.from({PANEL}.querySelectorAll('.jp-OutputArea-output[data-mime-type=\"application/vnd.jupyter.stderr\"]'))"
        ".map(e => e.textContent).filter(t => /Traceback|Error/.test(t))"
    )


def _duplicate_figures(driver) -> list[str]:
    return driver.execute_script(
        "const out = [];"
        f"{PANEL}.querySelectorAll('.jp-CodeCell').forEach((c, i) => {{"
        "  const srcs = Array.from(c.querySelectorAll('.jp-OutputArea-output img')).map(im => im.src);"
        "  if (new Set(srcs).size < srcs.length) out.push(i); });"
        "return out;"
    )


def _explorer(driver):
    """The last widget box on the page: its sliders, dropdowns and figure."""
    boxes = driver.execute_script(
        f"return Array.from({PANEL}.querySelectorAll('.jp-OutputArea-output .widget-vbox'))"
        ".filter(b => !b.parentElement.closest('.widget-vbox'));"
    )
    assert boxes, "no explorer widget rendered"
    box = boxes[-1]
    driver.execute_script("arguments[0].scrollIntoView({block: 'start'});", box)
    return box


def _figure(box):
    from selenium.webdriver.common.by import By

    imgs = box.find_elements(By.CSS_SELECTOR, ".widget-output img")
    return imgs[-1] if imgs else None


def _changes_figure(driver, box, act, label: str, name: str) -> None:
    before = _figure(box).get_attribute("src")
    act()
    img = wait(lambda: (f := _figure(box)) is not None and f.get_attribute("src") != before and f, 30,
                f"the figure to change after {label}")  # fmt: skip
    time.sleep(0.3)
    png = _shot(box, f"{name}-after-{label}")
    assert _not_blank(_shot(img, f"{name}-figure-after-{label}")), f"blank figure after {label}"
    assert len(png) > 10_000


def _slider_handles(box):
    from selenium.webdriver.common.by import By

    return box.find_elements(By.CSS_SELECTOR, ".noUi-handle")


def _readouts(box) -> dict[str, str]:
    from selenium.webdriver.common.by import By

    out = {}
    for w in box.find_elements(By.CSS_SELECTOR, ".widget-hslider"):
        label = w.find_elements(By.CSS_SELECTOR, ".widget-label")
        value = w.find_elements(By.CSS_SELECTOR, ".widget-readout")
        if label and value:
            out[label[0].text.strip()] = value[0].text.strip()
    return out


def _drive_explorer(driver, name: str, expected: dict[str, str], dropdown: bool) -> None:
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import Select

    box = _explorer(driver)
    wait(lambda: _figure(box), 30, "the explorer's figure")
    assert _not_blank(_shot(_figure(box), f"{name}-figure-before")), "blank figure before any input"
    _shot(box, f"{name}-before")
    shown = _readouts(box)
    for k, v in expected.items():
        assert shown.get(k) == v, f"{name}: slider {k!r} starts at {shown.get(k)!r}, the parameter is {v!r}"
    handles = _slider_handles(box)
    assert handles, "no slider"
    first = handles[0]
    _changes_figure(driver, box, lambda: ActionChains(driver).click_and_hold(first).move_by_offset(90, 0)
                    .release().perform(), "drag", name)  # fmt: skip
    second = _slider_handles(box)[1]

    def key():
        second.click()
        second.send_keys(Keys.ARROW_RIGHT)

    _changes_figure(driver, box, key, "arrow-key", name)
    if dropdown:
        select = Select(box.find_element(By.CSS_SELECTOR, ".widget-dropdown select"))
        _changes_figure(driver, box, lambda: select.select_by_index(len(select.options) - 1), "dropdown", name)


EXPLORERS = {
    "threshold_sensitivity": (
        # eps = "paper" for the first scene in the paper's order with results: corridor, 5 m
        {"eps (m)": f"{PAPER_EPS['corridor']:g}", "phi (deg)": "30", "delta (s)": "1", "tau (s)": "60"},
        True,
    ),
    "metrics_primer": ({"noise (m)": "0.00", "scale": "1.00", "wrong reloc at (s)": "off"}, False),
}


@pytest.mark.parametrize("name", DEFAULT_NOTEBOOKS)
def test_notebook_in_the_browser(lab, browser, name):
    url, root = lab
    try:
        _open_and_run(browser, url, name, timeout=240)
    except AssertionError as exc:
        if "every cell" not in str(exc) and "dialog" not in str(exc):
            raise
        # now and then (1 run in 3 here) one notebook's Run All never finishes in headless Chromium, a
        # different one each time, while the same notebook runs in seconds alone; once (CI) a dialog
        # stood in front of the menu: its picture is kept (results/browser/NAME-stuck.png or
        # NAME-dialog.png); once more, with fresh kernels, before calling it a failure, and then
        # with the end of the server's log (a kernel's death, say)
        _shut_down_kernels(url)
        try:
            _open_and_run(browser, url, name, timeout=240)
        except AssertionError as again:
            tail = (root / "lab.log").read_text(errors="replace")[-3000:]
            raise AssertionError(f"{again}\n(first try: {exc})\n--- the end of JupyterLab's log ---\n{tail}") from again
    errors = _errors(browser)
    assert not errors, f"{name}: error output: {errors[0][:500]}"
    assert not _duplicate_figures(browser), f"{name}: a figure shown twice in cell(s) {_duplicate_figures(browser)}"
    if name in EXPLORERS:
        expected, dropdown = EXPLORERS[name]
        _drive_explorer(browser, name, expected, dropdown)
    _shut_down_kernels(url)
    assert list((root / "tmp").glob(f"lorisnb-{name}-*")), f"{name}'s outputs are not in the lab's temporary folder"


def _shut_down_kernels(url: str) -> None:
    """Stop the notebook's kernel (the next notebook gets both cores)."""
    import urllib.request

    head = {"Authorization": f"token {TOKEN}"}
    with urllib.request.urlopen(urllib.request.Request(f"{url}/api/kernels", headers=head), timeout=10) as r:
        kernels = json.load(r)
    for k in kernels:
        req = urllib.request.Request(f"{url}/api/kernels/{k['id']}", headers=head, method="DELETE")
        urllib.request.urlopen(req, timeout=10).close()


@pytest.fixture(scope="module")
def offline_report(tmp_path_factory, icra20):
    """A report on a lab's results folder with trials (copies of bundled files, in a temporary folder)."""
    from report_fixtures import trial_results

    from lorisnb.tools.report.build import run_report

    root = tmp_path_factory.mktemp("report")
    results = trial_results(root / "mine", icra20)
    run_dir, runs = run_report(root / "run", {"quick": True}, ["per_sequence_benchmark", "threshold_sensitivity"],
                               progress=False, results=results)  # fmt: skip
    assert [r.status for r in runs] == ["ok", "ok"], [r.error for r in runs]
    return run_dir


def test_report_opens_offline(offline_report, tmp_path):
    """index.html and a notebook page from file://, with every http(s) request blocked and every
    request recorded (Chrome's performance log): none leaves the machine, nothing fails to load,
    and the first table of the page is a leaderboard."""
    with offline_pages(tmp_path / "chromium") as pages:
        driver = pages.driver
        for page in [offline_report / "index.html", offline_report / "report.html",
                     offline_report / "per_sequence_benchmark" / "per_sequence_benchmark.html",
                     offline_report / "threshold_sensitivity" / "threshold_sensitivity.html"]:  # fmt: skip
            pages.open(page, scroll=True, settle_s=1.0)  # scrolled: lazy images load
            if page.name in ("index.html", "report.html"):
                first = driver.execute_script("const t = document.querySelector('table'); return t && t.className")
                assert first == "leaderboard", f"{page.name}: the first table is {first!r}, not the leaderboard"
                head = driver.execute_script(
                    "return Array.from(document.querySelector('table').querySelectorAll('th')).map(t => t.textContent)"
                )
                assert head[:3] == ["rank", "algorithm", "cr"] and "coverage (sequences)" in head
    assert pages.outside() == [], f"requests that would leave the machine: {pages.outside()}"
    assert any(u.endswith(".png") for u in pages.requested)  # the figures came from the run folder


@pytest.fixture(scope="module")
def baseline_report(tmp_path_factory, offline_report, icra20):
    """A second report on the same results with ``--baseline``: the folder of earlier runs holds the
    first report with a fourth trial of ORB-SLAM2 on cafe 1 (which this run lacks: a failed run, so
    it regressed there), and a run at other thresholds (passed over as not comparable)."""
    import pandas as pd

    from lorisnb.tools.report.build import run_report

    root = tmp_path_factory.mktemp("baseline")
    earlier = root / "nightly"
    shutil.copytree(offline_report, earlier / "2026-11-01")
    table = earlier / "2026-11-01" / "findings" / "sequences.csv"
    t = pd.read_csv(table)
    here = (t["algorithm"] == "orb") & (t["scene"] == "cafe") & (t["seq"] == 1) & (t["trial"] == 1)
    pd.concat([t, t[here].assign(trial=4)], ignore_index=True).to_csv(table, index=False)
    t.assign(eps=0.5).to_csv(earlier / "other-thresholds.csv", index=False)
    results = offline_report.parent / "mine"  # the first report's results (its run.json says "{results}")
    assert json.loads((offline_report / "run.json").read_text())["spec"]["values"]["source"] == "{results}"
    run_dir, runs = run_report(root / "run", {"quick": True}, ["per_sequence_benchmark"], progress=False,
                               results=results, baseline=earlier, label="abc123")  # fmt: skip
    assert [r.status for r in runs] == ["ok"], [r.error for r in runs]
    return run_dir


def test_report_shows_what_changed_since_the_baseline(baseline_report, tmp_path):
    """The front page's "Since the baseline" in a real browser, offline: the verdict against the
    newest comparable earlier run, the regression named, the run at other thresholds passed over,
    the code under test, and the trend figure loaded."""
    driver = chromium(tmp_path / "chromium", offline=True)
    try:
        driver.get((baseline_report / "index.html").as_uri())
        wait(lambda: driver.execute_script("return document.readyState") == "complete", 30, "index.html")
        section = driver.execute_script(
            "const h = document.getElementById('since-baseline'); let t = ''; let e = h;"
            "while (e && (e === h || e.tagName !== 'H2')) { t += e.innerText + '\\n'; e = e.nextElementSibling; }"
            "return t;"
        )
        assert "Since the baseline" in section and "Against 2026-11-01" in section, section
        assert "regression" in section and "orb" in section and "cafe-1" in section, section
        assert "missing trial 4" in section, section
        assert "other-thresholds.csv" in section and "eps" in section, section  # passed over, with why
        assert "Code under test: abc123" in driver.find_element("tag name", "body").text
        loaded = driver.execute_script(
            "const i = document.querySelector(\"img[src='findings/trend_cr.svg']\"); return i && i.complete && i.naturalWidth"
        )
        assert loaded and loaded > 100, loaded
        driver.save_screenshot(str(SHOTS / "since_baseline.png")) if SHOTS.is_dir() else None
    finally:
        driver.quit()
    verdict = json.loads((baseline_report / "findings" / "since_baseline.json").read_text())
    assert verdict["baseline"] == "2026-11-01" and verdict["verdict"]["verdict"] == "regression"
