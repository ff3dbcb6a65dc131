"""A manifest received from someone else reads ground truth only inside its own folder and its
root (links resolved), unless --manifest-outside / outside=True says otherwise, and no error
quotes a file outside them."""

from __future__ import annotations

import shutil

import pytest

from lorisnb.cli import main
from lorisnb.errors import ParseError
from lorisnb.io.datasets.manifest import read_manifest

SECRET = "secret-first-line 1 2 3\n"


def manifest(folder, groundtruth, root="."):
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / "lab.toml"
    p.write_text(
        f'root = "{root}"\nestimate_format = "tum"\n[[session]]\nname = "desk"\ngroundtruth = "{groundtruth}"\n'
    )
    return p


@pytest.fixture
def secret(tmp_path):
    p = tmp_path / "private" / "notes.txt"
    p.parent.mkdir()
    p.write_text(SECRET)
    return p


@pytest.mark.parametrize("how", ["dotdot", "absolute", "link"])
def test_ground_truth_outside_the_manifest_folder_and_root_is_refused_unread(tmp_path, secret, capsys, how):
    folder = tmp_path / "shared" / "m"
    gt = {"dotdot": "../../private/notes.txt", "absolute": str(secret), "link": "gt.txt"}[how]
    m = manifest(folder, gt)
    if how == "link":
        (folder / "gt.txt").symlink_to(secret)
    with pytest.raises(ParseError, match="groundtruth lies outside the manifest's folder, its root"):
        read_manifest(m)
    res = tmp_path / "res" / "alg"
    res.mkdir(parents=True)
    (res / "desk.txt").write_text("1 0 0 0 0 0 0 1\n")
    rc = main(["evaluate", str(res.parent), "--manifest", str(m), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "outside the manifest's folder" in err and "secret-first-line" not in err
    assert read_manifest(m, outside=True).sessions[0].groundtruth.name in ("notes.txt", "gt.txt")
    rc = main(["evaluate", str(res.parent), "--manifest", str(m), "--manifest-outside", "--no-progress"])
    assert "outside the manifest's folder" not in capsys.readouterr().err  # read, as asked


def test_ground_truth_in_the_root_or_the_manifest_folder_is_read(tmp_path, data, capsys):
    tum = data.root / "tum-rgbd"
    m = manifest(tmp_path / "m", "fr2_desk_groundtruth.txt", root=str(tum))
    assert read_manifest(m).sessions[0].groundtruth == (tum / "fr2_desk_groundtruth.txt").resolve()
    shutil.copy(tum / "fr2_desk_groundtruth.txt", tmp_path / "m" / "gt.txt")
    read_manifest(manifest(tmp_path / "m", "gt.txt"))
    res = tmp_path / "res" / "orb"
    res.mkdir(parents=True)
    shutil.copy(tum / "fr2_desk_ORB.txt", res / "desk.txt")
    rc = main(["evaluate", str(res.parent), "--manifest", str(m), "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 0 and "orb" in out and "1/1" in out  # the session scored


def test_manifest_outside_needs_a_manifest(capsys, tmp_path):
    rc = main(["evaluate", str(tmp_path), "--manifest-outside", "--no-progress"])
    assert rc == 2 and "--manifest-outside: applies to" in capsys.readouterr().err


def test_a_root_written_in_the_manifest_elsewhere_is_refused_one_from_the_environment_is_not(
    tmp_path, secret, monkeypatch, capsys
):
    m = manifest(tmp_path / "shared" / "m", "notes.txt", root=str(secret.parent))
    with pytest.raises(ParseError, match="root = .* lies outside the manifest's folder"):
        read_manifest(m)
    monkeypatch.setenv("LAB_ROOT", str(secret.parent))  # the user's own setting, named as a dataset's: trusted
    monkeypatch.setenv("LORISNB_DATASET_VARIABLES", "LAB_ROOT")
    m = manifest(tmp_path / "shared" / "m", "notes.txt", root="${LAB_ROOT}")
    assert read_manifest(m).sessions[0].groundtruth == secret.resolve()


def _refused_unquoted(tmp_path, m, capsys) -> None:
    """``evaluate`` of a results folder with the manifest ``m``: refused (exit 2), the file outside unquoted."""
    res = tmp_path / "res" / "alg"
    res.mkdir(parents=True, exist_ok=True)
    (res / "desk.txt").write_text("1 0 0 0 0 0 0 1\n")
    rc = main(["evaluate", str(res.parent), "--manifest", str(m), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "lies outside" in err and "secret-first-line" not in err


@pytest.mark.parametrize("variable", ["HOME", "PWD", "TMPDIR"])
def test_a_root_in_a_variable_that_names_no_dataset_is_confined_like_a_written_one(
    tmp_path, secret, monkeypatch, capsys, variable
):
    """``root = "${HOME}"`` in a received manifest: the manifest chose the variable, and the user's
    home is no dataset: read only inside the manifest's folder or the data root, the content unquoted."""
    monkeypatch.setenv(variable, str(secret.parent))
    m = manifest(tmp_path / "shared" / "m", secret.name, root="${" + variable + "}")
    with pytest.raises(ParseError, match=r"root = .* lies outside the manifest's folder and lorisnb's data root"):
        read_manifest(m)
    _refused_unquoted(tmp_path, m, capsys)
    monkeypatch.setenv("LAB_ROOT", str(secret.parent))  # a dataset folder's variable: the user's own
    monkeypatch.setenv("LORISNB_DATASET_VARIABLES", "LAB_ROOT")
    m = manifest(tmp_path / "shared" / "m", secret.name, root="${LAB_ROOT}")
    assert read_manifest(m).sessions[0].groundtruth == secret.resolve()


def test_a_root_that_leaves_the_folder_its_variable_names_is_refused(tmp_path, secret, monkeypatch, capsys):
    """``root = "${HOME}/../.."``: the variable is the user's, the way out of it is the manifest's."""
    lab_root = tmp_path / "lab-data"
    lab_root.mkdir()
    monkeypatch.setenv("LAB_ROOT", str(lab_root))
    monkeypatch.setenv("LORISNB_DATASET_VARIABLES", "LAB_ROOT")
    up = "/".join([".."] * len(lab_root.parts)) + str(secret.parent)
    for root in ("${LAB_ROOT}/" + up, "$LAB_ROOT/../private"):
        m = manifest(tmp_path / "shared" / "m", "notes.txt", root=root)
        with pytest.raises(
            ParseError, match="lies outside the manifest's folder, the dataset folders its environment variables"
        ):
            read_manifest(m)
        _refused_unquoted(tmp_path, m, capsys)
    (lab_root / "V1").mkdir()
    m = manifest(tmp_path / "shared" / "m", "gt.txt", root="${LAB_ROOT}/V1")  # inside the variable's folder: read
    assert read_manifest(m).sessions[0].groundtruth == (lab_root / "V1" / "gt.txt").resolve()


@pytest.mark.parametrize("key", ["groundtruth", "root", "name"])
def test_a_nul_character_in_a_manifest_name_is_refused_naming_the_key(tmp_path, capsys, key):
    folder = tmp_path / "m"
    gt, root = ("gt\\u0000.txt", ".") if key == "groundtruth" else ("gt.txt", "a\\u0000" if key == "root" else ".")
    m = manifest(folder, gt, root=root)
    if key == "name":
        m.write_text(m.read_text().replace('name = "desk"', 'name = "de\\u0000sk"'))
    with pytest.raises(ParseError, match=f"{key} = .*: a NUL character"):
        read_manifest(m)
    rc = main(["evaluate", str(tmp_path), "--manifest", str(m), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and "a NUL character" in err and "Traceback" not in err


@pytest.mark.parametrize("target", ["secret", "folder"])
def test_an_estimate_linked_from_outside_the_results_folder_is_never_quoted(tmp_path, data, secret, capsys, target):
    """A session's estimate that is a link (to a file, or in an algorithm folder linked in from elsewhere)
    leading out of the results folder given is read as the user's own link, but an error about it names
    the line, never its content (``/etc/passwd`` linked into a received folder); --manifest-outside shows it."""
    tum = data.root / "tum-rgbd"
    m = manifest(tmp_path / "m", "fr2_desk_groundtruth.txt", root=str(tum))
    res = tmp_path / "res"
    res.mkdir()
    if target == "secret":
        (res / "alg").mkdir()
        (res / "alg" / "desk.txt").symlink_to(secret)
    else:  # an algorithm folder linked in from elsewhere
        (tmp_path / "elsewhere").mkdir()
        (tmp_path / "elsewhere" / "desk.txt").write_text(SECRET)
        (res / "alg").symlink_to(tmp_path / "elsewhere", target_is_directory=True)
    rc = main(["evaluate", str(res), "--manifest", str(m), "--no-progress"])
    err = capsys.readouterr().err
    how = "(a link leading" if target == "secret" else "(in the folder alg, a link leading"  # the file, or its folder
    assert rc == 1 and f"desk.txt, line 1: not a trajectory file as expected {how}" in err, err
    assert "outside the results folder: its content is not shown" in err and "secret-first-line" not in err
    rc = main(["evaluate", str(res), "--manifest", str(m), "--manifest-outside", "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 1 and "its content is not shown" not in err and "secret-first-line" in err  # shown, as asked


def test_an_estimate_linked_from_elsewhere_is_read_and_scored(tmp_path, data, capsys):
    tum = data.root / "tum-rgbd"
    m = manifest(tmp_path / "m", "fr2_desk_groundtruth.txt", root=str(tum))
    res = tmp_path / "res"
    (res / "alg").mkdir(parents=True)
    (res / "alg" / "desk.txt").symlink_to(tum / "fr2_desk_ORB.txt")  # kept with the data, linked in
    rc = main(["evaluate", str(res), "--manifest", str(m), "--no-progress"])
    assert rc == 0 and "1/1" in capsys.readouterr().out


@pytest.mark.parametrize("file_form", ["NFC", "NFD"])
def test_a_session_finds_its_estimate_whatever_the_unicode_form_of_its_file_name(tmp_path, data, file_form):
    """A session ``café`` (typed: NFC) finds ``café.txt`` saved by a Mac (NFD), and the other way round."""
    import unicodedata

    import lorisnb as ln

    tum = data.root / "tum-rgbd"
    folder = tmp_path / "m"
    folder.mkdir()
    name = unicodedata.normalize("NFD" if file_form == "NFC" else "NFC", "café")
    m = folder / "lab.toml"
    m.write_text(f'root = "{tum}"\n[[session]]\nname = "{name}"\ngroundtruth = "fr2_desk_groundtruth.txt"\n')
    res = tmp_path / "res" / "orb"
    res.mkdir(parents=True)
    shutil.copy(tum / "fr2_desk_ORB.txt", res / (unicodedata.normalize(file_form, "café") + ".txt"))
    ev = ln.evaluate_manifest(m, res.parent, progress=False, jobs=1)
    row = ev.sequences().iloc[0]
    assert len(ev.sequences()) == 1 and row["matched"] > 0 and not ev.failures


@pytest.mark.parametrize("kind", ["openloris", "tum"])
@pytest.mark.parametrize("target", ["secret", "folder"])
def test_a_file_linked_into_a_folder_evaluated_without_a_manifest_is_never_quoted(
    tmp_path, data, secret, capsys, kind, target
):
    """The same rule without a manifest: a results folder walked (OpenLORIS files, or TUM estimates
    against --gt) whose file, or algorithm folder, is a link leading out of it is read, but an
    error names the line, never the content; a file given by name on the command line is the
    user's own and is quoted as usual."""
    name = "cafe_1_1.txt" if kind == "openloris" else "desk.txt"
    res = tmp_path / "res"
    res.mkdir()
    if target == "secret":
        (res / "alg").mkdir()
        (res / "alg" / name).symlink_to(secret)
    else:
        (tmp_path / "elsewhere").mkdir()
        (tmp_path / "elsewhere" / name).write_text(SECRET)
        (res / "alg").symlink_to(tmp_path / "elsewhere", target_is_directory=True)
    how = (["--data", str(data.root)] if kind == "openloris"
           else ["--gt", str(data.root / "tum-rgbd" / "fr2_desk_groundtruth.txt"), "--format", "tum"])  # fmt: skip
    rc = main(["evaluate", str(res), *how, "--no-progress"])
    err = capsys.readouterr().err
    linked = "(a link leading" if target == "secret" else "(in the folder alg, a link leading"  # file, folder
    assert rc == 1 and f"{name}, line 1: not a trajectory file as expected {linked}" in err, err
    assert "its content is not shown)" in err and "--manifest-outside" not in err and "secret-first-line" not in err
    rc = main(["evaluate", str(res / "alg" / name), *how, "--no-progress"])  # named by the user: quoted
    err = capsys.readouterr().err
    assert rc != 0 and "secret-first-line" in err, err


@pytest.mark.parametrize("which", ["built-in", "own"])
def test_a_relative_root_variable_names_a_folder_of_the_current_directory(tmp_path, monkeypatch, which):
    """``TUM_ROOT=tumroot lorisnb evaluate ... --manifest tum-fr1-office`` looked for the ground truth
    in ``tumroot`` beside the manifest (inside the installed package for a built-in one): the folder
    is the shell's ``./tumroot``, as a shell user means it."""
    here = tmp_path / "cwd"
    (here / "tumroot" / "sub").mkdir(parents=True)
    monkeypatch.chdir(here)
    if which == "built-in":
        monkeypatch.setenv("TUM_ROOT", "tumroot")
        m = read_manifest("tum-fr1-office")
        assert all(s.groundtruth.parent == here / "tumroot" for s in m.sessions), m.sessions
    else:
        monkeypatch.setenv("MY_ROOT", "tumroot/")
        monkeypatch.setenv("LORISNB_DATASET_VARIABLES", "MY_ROOT")  # named a dataset's folder by the user
        m = read_manifest(manifest(tmp_path / "elsewhere", "gt.txt", root="${MY_ROOT}/sub"))
        assert m.sessions[0].groundtruth == here / "tumroot" / "sub" / "gt.txt"


@pytest.mark.parametrize("disk, written", [("NFD", "NFC"), ("NFC", "NFD")])
def test_a_manifests_ground_truth_and_root_are_found_in_another_unicode_form(
    tmp_path, data, capsys, monkeypatch, disk, written
):
    """``groundtruth = "dése.txt"`` (NFC) with the file spelled NFD on disk (copied from a Mac): not
    found, while estimates were; the files a manifest names are found as estimates are, in either form
    (its root folder too)."""
    import unicodedata

    def form(f, s):
        return unicodedata.normalize(f, s)

    folder = tmp_path / "lab"
    (folder / form(disk, "données")).mkdir(parents=True)
    shutil.copy(data.root / "tum-rgbd" / "freiburg1_xyz-groundtruth.txt", folder / form(disk, "données") / form(disk, "dése.txt"))  # fmt: skip
    m = manifest(folder, form(written, "dése.txt"), root=form(written, "données"))
    found = read_manifest(m).sessions[0].groundtruth
    assert found.is_file() and found.name == form(disk, "dése.txt")
    (tmp_path / "res" / "alg").mkdir(parents=True)
    shutil.copy(data.root / "tum-rgbd" / "freiburg1_xyz-rgbdslam.txt", tmp_path / "res" / "alg" / "desk.txt")
    monkeypatch.chdir(tmp_path)
    assert main(["evaluate", "res", "--manifest", str(m), "--no-progress"]) == 0, capsys.readouterr().err
