"""The challenge server in a real browser (Debian's headless Chromium through selenium, the
server on 127.0.0.1): a team opens the submit page, types its token, chooses its result files and
submits; the submission page shows the status, then the score (it reloads itself, no script);
the leaderboard then lists the team with that score; its team page and the organizer's admin page
open with their tokens. Every page is offline: no resource is loaded
from anywhere but the server."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pytest
from browser import chromium, need_chromium, wait
from challenge_fixtures import cafe_files, challenge_file

pytest.importorskip("fastapi")
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from challenge_load import free_port, kill, start_server  # noqa: E402

from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402

pytestmark = [pytest.mark.browser, pytest.mark.slow]


def test_team_submits_in_the_page_and_sees_its_score(tmp_path, data):
    need_chromium()
    from selenium.webdriver.common.by import By

    path = challenge_file(tmp_path, data)
    challenge = read_challenge(path)
    challenge.folder.mkdir(parents=True)
    engine = store.connect(challenge.database)
    token = store.add_team(engine, "browsers", time.time() + 7000)
    admin = store.add_team(engine, "organizers", time.time() + 7000, admin=True)
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    proc = start_server(path, port, tmp_path / "server.log")
    driver = chromium(tmp_path / "chromium", size="1200,900")
    try:
        driver.get(url + "/")
        assert "No scored submission yet" in driver.find_element(By.ID, "phase-development").text
        driver.get(url + "/submit")
        driver.find_element(By.ID, "token").send_keys(token)
        files = cafe_files(data, "orbslam2_rgbd")
        driver.find_element(By.ID, "files").send_keys("\n".join(str(p) for p in files))
        driver.find_element(By.ID, "send").click()
        wait(lambda: "/submissions/" in driver.current_url, 60, "the submission page")
        assert driver.find_element(By.ID, "team").text == "browsers"
        wait(lambda: driver.find_element(By.ID, "status").text == "scored", 240, "the score on the page")
        cells = driver.find_elements(By.CSS_SELECTOR, "#sequences td.cr")
        assert [c.text for c in cells] == ["0.999"]  # ORB-SLAM2 on cafe-1; cafe-2 is the final's, shown once it closes
        assert (
            "cafe 2 (cafe_1_2_orbslam2-original.txt): shown once phase 'final' closes"
            in driver.find_element(By.ID, "hidden-sequences").text
        )
        image = driver.find_element(By.CSS_SELECTOR, "img")
        assert driver.execute_script("return arguments[0].naturalWidth", image) > 100  # the timeline figure drawn

        def listed():
            driver.get(url + "/")
            board = driver.find_element(By.ID, "phase-development")
            return board if "browsers" in board.text else None

        board = wait(listed, 120, "the team on the leaderboard")
        row = board.find_element(By.CSS_SELECTOR, "table.board tr:nth-child(2)")
        assert row.find_element(By.CSS_SELECTOR, "td.team").text == "browsers"
        assert row.find_element(By.CSS_SELECTOR, "td.value").text == "0.999"
        resources = driver.execute_script("return performance.getEntriesByType('resource').map(e => e.name)")
        assert all(r.startswith(url) for r in resources)  # offline: nothing from a CDN
        driver.get(url + "/team")
        driver.find_element(By.ID, "token").send_keys(token)
        driver.find_element(By.ID, "open").click()  # a form: the team's page replaces this one
        wait(lambda: "4 submission(s) left" in driver.find_element(By.TAG_NAME, "body").text, 30, "the team's page")
        # the admin's page: every team, and the final's sequence scored but marked hidden from teams
        driver.get(url + "/admin")
        driver.find_element(By.ID, "token").send_keys(admin)
        driver.find_element(By.ID, "open").click()
        teams = wait(lambda: driver.find_element(By.ID, "teams").text, 30, "the admin's page")
        assert "browsers" in teams and "organizers" in teams
        scores = [c.text for c in driver.find_elements(By.CSS_SELECTOR, "td.scores")]
        assert any("cafe 2: " in c and "(hidden from teams)" in c for c in scores), scores
        assert driver.find_element(By.ID, "admin-only").is_displayed()
        resources = driver.execute_script("return performance.getEntriesByType('resource').map(e => e.name)")
        assert all(r.startswith(url) for r in resources)
    finally:
        driver.quit()
        kill(proc)
