"""The vendored uPlot chart library (omsd/web/static/vendor/) and scripts/refresh_uplot.py.

The dashboard is served offline, so uPlot is kept in the package, pinned by uplot.json (exact
version, tarball, npm integrity, each file's sha256) with its MIT licence. These tests check the
files against the pin, the licence's text, the pin's form, the script's --check mode, that the
installed package can read the files, and the script's refusals on a bad tarball, with the
registry replaced by local bytes. Nothing here reaches the network.
"""

from __future__ import annotations

import base64
import hashlib
import importlib.resources
import importlib.util
import io
import json
import re
import shutil
import subprocess
import sys
import tarfile
import tomllib
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parent.parent.parent
VENDOR = ROOT / "omsd" / "web" / "static" / "vendor"
MANIFEST = VENDOR / "uplot.json"
SCRIPT = ROOT / "scripts" / "refresh_uplot.py"
EXPECTED_FILES = {"uPlot.iife.min.js", "uPlot.min.css", "LICENSE.uPlot"}


def manifest() -> dict[str, object]:
    """The pin, as written by scripts/refresh_uplot.py."""
    data: dict[str, object] = json.loads(MANIFEST.read_text(encoding="utf-8"))
    return data


def listed_files() -> dict[str, str]:
    """The vendored files' names and their recorded sha256."""
    files = manifest()["files"]
    assert isinstance(files, dict)
    return files


@pytest.fixture(scope="module")
def script() -> ModuleType:
    """scripts/refresh_uplot.py, imported as a module (it is not part of the package)."""
    spec = importlib.util.spec_from_file_location("refresh_uplot", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# -- the vendored files against the pin -----------------------------------------------------------


def test_the_pin_lists_the_three_vendored_files() -> None:
    assert set(listed_files()) == EXPECTED_FILES


@pytest.mark.parametrize("name", sorted(EXPECTED_FILES))
def test_each_listed_file_exists_with_its_recorded_sha256(name: str) -> None:
    path = VENDOR / name
    assert path.is_file(), f"{path} is missing"
    assert hashlib.sha256(path.read_bytes()).hexdigest() == listed_files()[name]


def test_uplot_json_is_written_with_sorted_keys_indent_2_and_a_final_newline() -> None:
    text = MANIFEST.read_text(encoding="utf-8")
    assert text == json.dumps(json.loads(text), sort_keys=True, indent=2) + "\n"


# -- the licence ----------------------------------------------------------------------------------


def test_the_licence_is_uplots_mit_licence_by_leon_sorokin() -> None:
    text = (VENDOR / "LICENSE.uPlot").read_text(encoding="utf-8")
    assert text.startswith("The MIT License (MIT)")
    assert re.search(r"^Copyright \(c\) \d{4} Leon Sorokin$", text, re.MULTILINE)
    assert "Permission is hereby granted, free of charge, to any person obtaining a copy" in text
    assert "The above copyright notice and this permission notice shall be included" in text
    assert 'THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND' in text


# -- the pin's form -------------------------------------------------------------------------------


def test_the_version_is_pinned_exactly() -> None:
    data = manifest()
    assert data["package"] == "uplot"
    assert isinstance(data["version"], str)
    assert re.fullmatch(r"\d+\.\d+\.\d+", data["version"])


def test_the_tarball_address_is_the_registrys_for_the_pinned_version() -> None:
    data = manifest()
    version = data["version"]
    assert data["tarball"] == f"https://registry.npmjs.org/uplot/-/uplot-{version}.tgz"


def test_the_integrity_is_an_sha512_sri_string() -> None:
    integrity = manifest()["integrity"]
    assert isinstance(integrity, str)
    algorithm, _, digest = integrity.partition("-")
    assert algorithm == "sha512"
    assert len(base64.b64decode(digest, validate=True)) == hashlib.sha512().digest_size


def test_the_minified_script_is_the_pinned_version() -> None:
    """uPlot's build puts its version in the first line's banner comment."""
    first_line = (VENDOR / "uPlot.iife.min.js").read_text(encoding="utf-8").partition("\n")[0]
    assert f"uPlot (v{manifest()['version']})" in first_line


# -- the script's --check mode --------------------------------------------------------------------


def run_check(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(SCRIPT), "--check", *args],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )


def test_check_passes_on_the_vendored_files() -> None:
    result = run_check()
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""


def test_check_fails_naming_a_changed_file_and_a_missing_one(tmp_path: Path) -> None:
    for path in VENDOR.iterdir():
        shutil.copyfile(path, tmp_path / path.name)
    with (tmp_path / "uPlot.min.css").open("a", encoding="utf-8") as css:
        css.write("/* edited */\n")
    (tmp_path / "LICENSE.uPlot").unlink()

    result = run_check("--vendor-dir", str(tmp_path))

    assert result.returncode == 1
    lines = result.stderr.splitlines()
    assert len(lines) == 2
    assert "LICENSE.uPlot: missing" in lines[0]
    assert "uPlot.min.css: sha256" in lines[1]
    assert "uPlot.iife.min.js" not in result.stderr


# -- the installed package ships the files --------------------------------------------------------


@pytest.mark.parametrize("name", sorted(EXPECTED_FILES))
def test_the_installed_package_ships_the_file(name: str) -> None:
    resource = importlib.resources.files("omsd.web") / "static" / "vendor" / name
    assert resource.is_file()
    assert resource.read_bytes() == (VENDOR / name).read_bytes()


def test_the_installed_package_ships_the_minified_script_as_text() -> None:
    resource = importlib.resources.files("omsd.web") / "static" / "vendor" / "uPlot.iife.min.js"
    assert "uPlot" in resource.read_text(encoding="utf-8")


def test_the_package_data_covers_the_vendor_directory() -> None:
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    patterns = pyproject["tool"]["setuptools"]["package-data"]["omsd.web"]
    assert "static/vendor/*" in patterns


# -- refusals, with the registry replaced by local bytes ------------------------------------------


def make_tarball(members: dict[str, bytes]) -> bytes:
    """A gzipped tarball holding the given members, as npm packs them."""
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tar:
        for name, data in members.items():
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    return buffer.getvalue()


def sri(data: bytes) -> str:
    return "sha512-" + base64.b64encode(hashlib.sha512(data).digest()).decode("ascii")


FAKE_MEMBERS = {
    "package/dist/uPlot.iife.min.js": b"/*! uPlot (v9.9.9) */\nvar uPlot=1;\n",
    "package/dist/uPlot.min.css": b".uplot{}\n",
    "package/LICENSE": b"The MIT License (MIT)\n",
    "package/dist/uPlot.esm.js": b"export default 1;\n",
}


def fake_registry(
    monkeypatch: pytest.MonkeyPatch, script: ModuleType, tarball: bytes, integrity: str
) -> list[str]:
    """Answer the script's fetches from memory; return the list of fetched addresses."""
    tarball_url = "https://registry.npmjs.org/uplot/-/uplot-9.9.9.tgz"
    metadata = {
        "name": "uplot",
        "version": "9.9.9",
        "dist": {"tarball": tarball_url, "integrity": integrity},
    }
    answers = {
        "https://registry.npmjs.org/uplot/9.9.9": json.dumps(metadata).encode(),
        tarball_url: tarball,
    }
    fetched: list[str] = []

    def fetch(url: str) -> bytes:
        fetched.append(url)
        return answers[url]

    monkeypatch.setattr(script, "fetch", fetch)
    return fetched


def test_a_verified_tarball_is_vendored_with_only_the_three_files(
    script: ModuleType, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    tarball = make_tarball(FAKE_MEMBERS)
    fake_registry(monkeypatch, script, tarball, sri(tarball))

    assert script.main(["--version", "9.9.9", "--vendor-dir", str(tmp_path)]) == 0

    assert {path.name for path in tmp_path.iterdir()} == EXPECTED_FILES | {"uplot.json"}
    assert (tmp_path / "LICENSE.uPlot").read_bytes() == FAKE_MEMBERS["package/LICENSE"]
    pin = json.loads((tmp_path / "uplot.json").read_text(encoding="utf-8"))
    assert pin["version"] == "9.9.9"
    assert pin["integrity"] == sri(tarball)
    assert script.check(tmp_path) == []


def test_a_tarball_that_does_not_match_its_integrity_is_refused(
    script: ModuleType,
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    tarball = make_tarball(FAKE_MEMBERS)
    fake_registry(monkeypatch, script, tarball, sri(tarball + b"tampered"))

    assert script.main(["--version", "9.9.9", "--vendor-dir", str(tmp_path)]) == 2

    assert list(tmp_path.iterdir()) == []
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1
    assert "integrity mismatch" in err


def test_a_tarball_without_a_wanted_file_is_refused(
    script: ModuleType,
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    members = {k: v for k, v in FAKE_MEMBERS.items() if k != "package/LICENSE"}
    tarball = make_tarball(members)
    fake_registry(monkeypatch, script, tarball, sri(tarball))

    assert script.main(["--version", "9.9.9", "--vendor-dir", str(tmp_path)]) == 2

    assert list(tmp_path.iterdir()) == []
    assert "package/LICENSE is not in the tarball" in capsys.readouterr().err


def test_a_version_that_is_not_exact_is_refused_before_any_fetch(
    script: ModuleType, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    fetched = fake_registry(monkeypatch, script, b"", "sha512-")

    for version in ("latest", "^1.6.0", "1.6"):
        assert script.main(["--version", version, "--vendor-dir", str(tmp_path)]) == 2

    assert fetched == []
