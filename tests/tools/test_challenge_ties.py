"""Identical results on the leaderboard, through the server's API. Team ``zeta`` uploads the icra20
ORB-SLAM2 run of cafe-1-1, then ``alpha8`` the same file 8 times as trials: pandas' mean of the 8
copies of the C-ATE 0.4725435807036217 is ...216, which won the C-ATE tie-break (``alpha8`` was
listed first), and the row's ``cr`` (a second computation of the CR) differed from its ``value``.
Ranked on C-ATE, compare's own value of 3 copies (``zeta3``, uploaded first) was a unit of the last
place above the run's uploaded once (``alpha``, later): ``alpha`` went first, and the sentence under
the board, worded from the report's order by value, named it. Now the trials' means are exact, the
order within a rank compares values to 12 significant digits (then the earlier submission), the
metric's column is the value itself, and the sentence is worded from the table as ordered.

And a file whose name starts with a space (the icra20 DS-SLAM files are named ``' home-1-1.txt'``)
is refused naming that character and its position, and listing every character a name may hold."""

from __future__ import annotations

import re
import time

import pytest
from challenge_fixtures import challenge_file, wait_scored, zipped

import lorisnb as ln

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from lorisnb.tools.challenge import store  # noqa: E402
from lorisnb.tools.challenge.app import create_app  # noqa: E402
from lorisnb.tools.challenge.board import ORDER_DIGITS  # noqa: E402
from lorisnb.tools.challenge.config import read_challenge  # noqa: E402
from lorisnb.tools.challenge.uploads import NAME_FIRST, NAME_MAX, NAME_REST  # noqa: E402

ORB = ("orbslam2_rgbd", "cafe_1_1_orbslam2-original.txt")


def _board(client) -> dict:
    for _ in range(300):
        phases = client.get("/api/leaderboard").json()["phases"]
        if not any(p.get("updating") for p in phases):
            return next(p for p in phases if p["phase"] == "development")
        time.sleep(0.2)
    raise AssertionError("the leaderboard was not updated within a minute")


def _served(tmp, data, teams: tuple[str, ...], metric: str = "cr"):
    path = challenge_file(tmp, data)
    path.write_text(path.read_text().replace('title = "Class challenge"\n', f'title = "Ties"\nmetric = "{metric}"\n'))
    app = create_app(read_challenge(path))
    tokens = {t: store.add_team(app.state.server.engine, t, time.time() + 7000) for t in teams}
    return TestClient(app), tokens


@pytest.fixture(scope="module")
def server(tmp_path_factory, data):
    client, tokens = _served(tmp_path_factory.mktemp("ties"), data, ("zeta", "alpha8", "spaced"))
    with client:
        yield client, tokens


def _post(client, token: str, files: list) -> dict:
    r = client.post("/api/submissions", files=files, headers={"Authorization": f"Bearer {token}"})
    return dict(status=r.status_code, body=r.json())


def _copies(body: bytes, n: int) -> list:
    """The upload of ``body`` (cafe-1-1) as it is (``n`` 1), or as ``n`` trials in one .zip."""
    if n == 1:
        return [("files", (ORB[1], body))]
    return [("files", ("t.zip", zipped({f"cafe-1-1_trial{k}.txt": body for k in range(1, n + 1)})))]


def _ranked(client, tokens: dict, body: bytes, uploads: dict[str, int]) -> dict:
    """The development board once each team has uploaded its copies of cafe-1-1, one after the other
    (their submission times are their order)."""
    for team, n in uploads.items():
        r = _post(client, tokens[team], _copies(body, n))
        assert r["status"] == 201, r
        view = wait_scored(client, r["body"]["id"])
        assert view["status"] == "scored", view
    return _board(client)


def _table_order(client) -> list[str]:
    """The teams of the development board's table, as the page lists them."""
    page = client.get("/").text
    section = page[page.index('id="phase-development"') :]
    section = section[: section.index("</section>")]
    return re.findall(r'<td class="team">([^<]*)</td>', section)


def test_identical_results_are_ordered_by_the_earlier_submission_one_number_everywhere(server, data):
    client, tokens = server
    board = _ranked(client, tokens, (data.icra20 / "per-seq" / ORB[0] / ORB[1]).read_bytes(), {"zeta": 1, "alpha8": 8})
    rows = [r for r in board["rows"] if r["scene"] == "cafe"]
    assert [r["team"] for r in rows] == ["zeta", "alpha8"]
    assert [r["position"] for r in rows] == [1, 2] and {r["rank"] for r in rows} == {1}
    assert rows[0]["submitted"] < rows[1]["submitted"]
    # the trials' mean of a copied run is the run's own value, to the last bit (pandas' was a unit of the last
    # place off); the run's own, as lorisnb evaluates the file: its last bit is the BLAS's (row_sums' matrix
    # products), 0.4725435807036217 until this machine's packages changed on 2026-12-01, then ...2135 (numpy 2.4.6)
    own = ln.evaluate(data.icra20 / "per-seq" / ORB[0] / ORB[1], progress=False).sequence_rows()[0]
    assert [r["c_ate_rmse"] for r in rows] == [own["c_ate_rmse"]] * 2
    assert own["c_ate_rmse"] == pytest.approx(0.4725435807036217, rel=1e-14)
    for r in rows:  # the CR column is the value ranked on, not a second computation of it
        assert r["cr"] == r["value"] == own["cr"] == pytest.approx(0.9994697642387167, rel=1e-14)
    (said,) = [s for s in board["sentences"] if s.startswith("In cafe")]
    assert said.startswith("In cafe, zeta has the highest correct rate CR"), said
    assert _table_order(client) == ["zeta", "alpha8"]
    assert said in client.get("/").text


def test_values_equal_to_12_digits_are_ordered_by_submission_and_the_sentence_follows(tmp_path, data):
    """Ranked on C-ATE: compare's scene value of 3 copies of the run is 0.47254358070362174, of the run
    itself 0.4725435807036217; ``zeta3`` (3 copies, submitted first) goes first, its C-ATE column is
    its value, and the sentence names it (the report's order, by value, named ``alpha``)."""
    client, tokens = _served(tmp_path, data, ("zeta3", "alpha"), metric="c_ate_rmse")
    with client:
        body = (data.icra20 / "per-seq" / ORB[0] / ORB[1]).read_bytes()
        board = _ranked(client, tokens, body, {"zeta3": 3, "alpha": 1})
        rows = [r for r in board["rows"] if r["scene"] == "cafe"]
        assert [r["team"] for r in rows] == ["zeta3", "alpha"]
        assert {r["rank"] for r in rows} == {1}
        values = [r["value"] for r in rows]
        # compare's values of the two differed in their last bit when this was written (...174 and ...17);
        # the order holds whether they differ or not
        assert {f"{v:.{ORDER_DIGITS}g}" for v in values} == {"0.472543580704"}
        for r in rows:
            assert r["c_ate_rmse"] == r["value"]
        (said,) = [s for s in board["sentences"] if s.startswith("In cafe")]
        assert said.startswith("In cafe, zeta3 has the lowest ATE RMSE over correct poses C-ATE (m)"), said
        assert _table_order(client) == ["zeta3", "alpha"]


def test_a_name_starting_with_a_space_is_refused_naming_the_space_and_what_a_name_may_hold(server, data):
    client, tokens = server
    body = (data.icra20 / "per-seq" / "ds-slam" / " home-1-1.txt").read_bytes()
    r = _post(client, tokens["spaced"], [("files", ("ds.zip", zipped({" home-1-1.txt": body})))])
    assert r["status"] == 400, r
    said = r["body"]["detail"] if isinstance(r["body"].get("detail"), str) else str(r["body"])
    assert "' home-1-1.txt'" in said
    assert "character 1 is a space, which cannot start a name" in said, said
    assert "rename it 'home-1-1.txt'" in said, said
    # every character the check takes is listed in the message, from the check's own definition
    for c in sorted(set(NAME_REST) - set(NAME_FIRST) - {" "}):
        assert f"'{c}'" in said, (c, said)
    assert "spaces" in said and f"1 to {NAME_MAX} characters" in said
    # and a name the message says is taken is taken: inner spaces and ,+=@() (an OpenLORIS result file)
    orb = (data.icra20 / "per-seq" / ORB[0] / ORB[1]).read_bytes()
    r = _post(client, tokens["spaced"], [("files", ("orb slam (run=1,a+b@c).txt", orb))])
    assert r["status"] == 201, r


@pytest.mark.parametrize(
    ("name", "said"),
    [
        ("cafe-1-1#2.txt", "character 9 is '#', which a name cannot hold"),
        ("_cafe-1-1.txt", "character 1 is '_', which cannot start a name"),
        ("café-1-1.txt", "character 4 is 'é' (U+00E9), which a name cannot hold"),
        ("c" * (NAME_MAX + 1) + ".txt", f"{NAME_MAX + 5} characters long"),
    ],
)
def test_other_refused_names_say_which_character(server, name, said):
    client, tokens = server
    r = _post(client, tokens["spaced"], [("files", (name, b"1 0 0 0 0 0 0 1\n"))])
    assert r["status"] == 400, r
    assert said in str(r["body"]), r["body"]
