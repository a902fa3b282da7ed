#!/usr/bin/env python3
"""Vendor the uPlot chart library (npm package ``uplot``, MIT) for the web dashboard.

The dashboard is served offline, so uPlot is not loaded from a CDN: three files from the npm
package are kept in ``omsd/web/static/vendor/`` and shipped as package data:

* ``uPlot.iife.min.js`` (from ``package/dist/uPlot.iife.min.js``), the browser build;
* ``uPlot.min.css`` (from ``package/dist/uPlot.min.css``), its style sheet;
* ``LICENSE.uPlot`` (from ``package/LICENSE``), its MIT licence, which must travel with it.

``uplot.json`` next to them is the pin: the exact version, the tarball's address, its npm
integrity (``sha512-<base64>``) and the sha256 of each vendored file.

Usage, from the repository's root:

    python scripts/refresh_uplot.py                   # fetch the pinned version again
    python scripts/refresh_uplot.py --version 1.6.32  # move the pin to another exact version
    python scripts/refresh_uplot.py --check           # download nothing; do the files match?

A refresh asks the npm registry for ``https://registry.npmjs.org/uplot/<version>``, downloads
the tarball named by its ``dist.tarball``, checks it against ``dist.integrity`` and only then
writes the three files and ``uplot.json``. It refuses (exit status 2, one line on stderr) if the
tarball does not match its integrity, if the registry's integrity for the pinned version is not
the one already recorded in ``uplot.json`` (a published npm version never changes), if the
version is not exact (``1.2.3``; no ranges or tags), or if a file is missing from the tarball.

``--check`` exits 0 when every file listed in ``uplot.json`` is present with the recorded
sha256, and 1 otherwise, naming each file that is missing or differs. It needs no network.

Only the standard library is used, so the script runs with any Python 3.11 or newer.
"""

from __future__ import annotations

import argparse
import base64
import hashlib
import hmac
import io
import json
import re
import sys
import tarfile
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

PACKAGE = "uplot"
REGISTRY = "https://registry.npmjs.org"
ROOT = Path(__file__).resolve().parent.parent
VENDOR_DIR = ROOT / "omsd" / "web" / "static" / "vendor"
MANIFEST_NAME = "uplot.json"
# member of the npm tarball -> name in the vendor directory
FILES = {
    "package/dist/uPlot.iife.min.js": "uPlot.iife.min.js",
    "package/dist/uPlot.min.css": "uPlot.min.css",
    "package/LICENSE": "LICENSE.uPlot",
}
EXACT_VERSION = re.compile(r"\d+\.\d+\.\d+")
TIMEOUT = 60  # seconds, for each request to the registry


class Refused(Exception):
    """A refresh that must not write anything; the message is the one line printed."""


def sha256_hex(data: bytes) -> str:
    """The sha256 of data, as lower-case hex."""
    return hashlib.sha256(data).hexdigest()


def verify_integrity(data: bytes, integrity: str) -> None:
    """Raise Refused unless data matches an npm integrity string (``sha512-<base64>``)."""
    algorithm, _, expected = integrity.strip().partition("-")
    if algorithm != "sha512" or not expected:
        raise Refused(f"unsupported integrity {integrity!r}: expected sha512-<base64>")
    actual = base64.b64encode(hashlib.sha512(data).digest()).decode("ascii")
    if not hmac.compare_digest(actual, expected):
        raise Refused(f"integrity mismatch: expected sha512-{expected}, got sha512-{actual}")


def extract(tarball: bytes) -> dict[str, bytes]:
    """The vendored files' contents, by their vendored names, read from an npm tarball.

    Only the members named in FILES are read, as regular files, and nothing is written.
    """
    result: dict[str, bytes] = {}
    try:
        with tarfile.open(fileobj=io.BytesIO(tarball), mode="r:gz") as tar:
            for member_name, vendored_name in FILES.items():
                try:
                    member = tar.getmember(member_name)
                except KeyError:
                    raise Refused(f"{member_name} is not in the tarball") from None
                stream = tar.extractfile(member) if member.isfile() else None
                if stream is None:
                    raise Refused(f"{member_name} in the tarball is not a regular file")
                result[vendored_name] = stream.read()
    except (tarfile.TarError, OSError, EOFError) as error:
        raise Refused(f"cannot read the tarball: {error}") from None
    return result


def fetch(url: str) -> bytes:
    """The body of an HTTPS GET, or Refused with the reason."""
    if not url.startswith("https://"):
        raise Refused(f"refusing a non-HTTPS address: {url}")
    request = urllib.request.Request(url, headers={"User-Agent": "omsd-refresh-uplot"})
    try:
        with urllib.request.urlopen(request, timeout=TIMEOUT) as response:
            body: bytes = response.read()
            return body
    except (urllib.error.URLError, OSError) as error:
        raise Refused(f"cannot fetch {url}: {error}") from None


def read_manifest(vendor_dir: Path) -> dict[str, Any] | None:
    """The pin (uplot.json) in vendor_dir, or None if there is none yet."""
    path = vendor_dir / MANIFEST_NAME
    if not path.exists():
        return None
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise Refused(f"cannot read {path}: {error}") from None
    if not isinstance(manifest, dict):
        raise Refused(f"{path} is not a JSON object")
    return manifest


def refresh(vendor_dir: Path, version: str | None) -> dict[str, Any]:
    """Download, verify and write the vendored files and uplot.json; return the new pin."""
    pinned = read_manifest(vendor_dir)
    if version is None:
        if pinned is None:
            raise Refused(f"no {MANIFEST_NAME} in {vendor_dir}: pass --version X.Y.Z to pin one")
        version = str(pinned["version"])
    if not EXACT_VERSION.fullmatch(version):
        raise Refused(f"version {version!r} is not exact (X.Y.Z)")

    try:
        metadata = json.loads(fetch(f"{REGISTRY}/{PACKAGE}/{version}"))
        name, answered = metadata.get("name"), metadata.get("version")
        tarball_url = str(metadata["dist"]["tarball"])
        integrity = str(metadata["dist"]["integrity"])
    except (ValueError, KeyError, TypeError, AttributeError) as error:
        raise Refused(f"unexpected registry metadata for {PACKAGE}@{version}: {error!r}") from None
    if name != PACKAGE or answered != version:
        raise Refused(f"the registry answered for {name}@{answered}, not {PACKAGE}@{version}")
    if pinned is not None and pinned.get("version") == version and pinned["integrity"] != integrity:
        raise Refused(
            f"the registry's integrity for {PACKAGE}@{version} ({integrity}) is not the pinned "
            f"one ({pinned['integrity']})"
        )

    tarball = fetch(tarball_url)
    verify_integrity(tarball, integrity)
    contents = extract(tarball)

    vendor_dir.mkdir(parents=True, exist_ok=True)
    for name, data in contents.items():
        (vendor_dir / name).write_bytes(data)
    manifest = {
        "package": PACKAGE,
        "version": version,
        "tarball": tarball_url,
        "integrity": integrity,
        "files": {name: sha256_hex(data) for name, data in contents.items()},
    }
    text = json.dumps(manifest, sort_keys=True, indent=2) + "\n"
    (vendor_dir / MANIFEST_NAME).write_text(text, encoding="utf-8")
    return manifest


def check(vendor_dir: Path) -> list[str]:
    """What is wrong with the vendored files against uplot.json: one line each, empty if none."""
    manifest = read_manifest(vendor_dir)
    if manifest is None:
        return [f"{vendor_dir / MANIFEST_NAME} is missing"]
    problems: list[str] = []
    for name, expected in sorted(manifest.get("files", {}).items()):
        path = vendor_dir / name
        if not path.is_file():
            problems.append(f"{name}: missing")
        elif (actual := sha256_hex(path.read_bytes())) != expected:
            problems.append(f"{name}: sha256 {actual} differs from {expected} in {MANIFEST_NAME}")
    missing_from_manifest = sorted(set(FILES.values()) - set(manifest.get("files", {})))
    problems.extend(f"{name}: not listed in {MANIFEST_NAME}" for name in missing_from_manifest)
    return problems


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status."""
    parser = argparse.ArgumentParser(
        description="Vendor uPlot from the npm registry, pinned and verified."
    )
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--version", help="move the pin to this exact version (X.Y.Z)")
    mode.add_argument(
        "--check", action="store_true", help="download nothing; verify the files' sha256"
    )
    parser.add_argument(
        "--vendor-dir",
        type=Path,
        default=VENDOR_DIR,
        help=f"where the files and {MANIFEST_NAME} are (default: %(default)s)",
    )
    args = parser.parse_args(argv)

    if args.check:
        try:
            problems = check(args.vendor_dir)
        except Refused as error:
            problems = [str(error)]
        for problem in problems:
            print(f"refresh_uplot: {problem}", file=sys.stderr)
        if problems:
            return 1
        print(f"refresh_uplot: the vendored files match {MANIFEST_NAME}")
        return 0

    try:
        manifest = refresh(args.vendor_dir, args.version)
    except Refused as error:
        print(f"refresh_uplot: refused: {error}", file=sys.stderr)
        return 2
    sizes = ", ".join(
        f"{name} ({(args.vendor_dir / name).stat().st_size} bytes)" for name in manifest["files"]
    )
    print(f"refresh_uplot: {PACKAGE} {manifest['version']} vendored: {sizes}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
