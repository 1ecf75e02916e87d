#!/usr/bin/python3
"""The Unity package as Unity's package manager takes it (scripts/unity-package check): the
package itself passes; and a copy broken in each way Unity would refuse or ignore fails, naming
what is wrong, so the check is known to catch each.
Usage: package_layout_test.py SOURCE_DIR"""
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile

source = pathlib.Path(sys.argv[1])
tool = source / "scripts" / "unity-package"
package = source / "bindings" / "unity" / "com.hapticd.client"


def run(folder):
    result = subprocess.run([sys.executable, str(tool), "check", str(folder)], capture_output=True,
                            text=True, timeout=60)
    return result.returncode, result.stdout + result.stderr


failures = []
status, output = run(package)
print(output, end="")
if status != 0:
    failures.append("the package itself fails the check")


def broken(name, expected, breaking):
    """Copies the package, breaks it with `breaking(copy)`, and expects the check to fail saying `expected`."""
    with tempfile.TemporaryDirectory() as temporary:
        copy = pathlib.Path(temporary) / package.name
        shutil.copytree(package, copy)
        breaking(copy)
        status, output = run(copy)
        if status == 0 or expected not in output:
            failures.append(f"{name}: expected a failure saying {expected!r}, got {status}:\n{output}")
        else:
            print(f"{name}: refused as it should be: {expected}")


def edit_manifest(copy, **changes):
    manifest = json.loads((copy / "package.json").read_text())
    manifest.update(changes)
    (copy / "package.json").write_text(json.dumps(manifest))


broken("a script without its .meta", "Runtime/Client.cs: has no .meta",
       lambda c: (c / "Runtime" / "Client.cs.meta").unlink())
broken("a new file without its .meta", "Runtime/Extra.cs: has no .meta",
       lambda c: (c / "Runtime" / "Extra.cs").write_text("// new\n"))
broken("a folder without its .meta", "Runtime: has no .meta", lambda c: (c / "Runtime.meta").unlink())
broken("a .meta left behind", "Runtime/Gone.cs.meta: a .meta whose asset is not there",
       lambda c: shutil.copy(c / "Runtime" / "Client.cs.meta", c / "Runtime" / "Gone.cs.meta"))
broken("two assets with one GUID", "is also",
       lambda c: shutil.copy(c / "Runtime" / "Client.cs.meta", c / "Runtime" / "Types.cs.meta"))
broken("a GUID that is not one", "has no guid",
       lambda c: (c / "README.md.meta").write_text("fileFormatVersion: 2\nguid: not-a-guid\n"))
broken("a folder's .meta that does not say so", "folderAsset: yes",
       lambda c: shutil.copy(c / "README.md.meta", c / "Runtime.meta"))
broken("an upper-case package name", "name must be lower-case",
       lambda c: edit_manifest(c, name="com.Hapticd.Client"))
broken("a version that is not semantic", "version must be Semantic Versioning",
       lambda c: edit_manifest(c, version="1.0"))
broken("a Unity version in the wrong form", "unity must be 'YYYY.N'",
       lambda c: edit_manifest(c, unity="2021.3.1f1"))
broken("a sample outside Samples~", "samples[0].path",
       lambda c: edit_manifest(c, samples=[{"displayName": "x", "description": "x", "path": "Runtime"}]))
broken("a changelog without the version", "CHANGELOG.md: has no entry",
       lambda c: edit_manifest(c, version="9.9.9"))
broken("an .asmdef named otherwise than its file", "name must be the file's",
       lambda c: (c / "Runtime" / "Hapticd.Runtime.asmdef").write_text('{"name": "Other"}'))
broken("a platform Unity does not know", "is not a platform Unity knows",
       lambda c: (c / "Runtime" / "Hapticd.Runtime.asmdef").write_text(
           '{"name": "Hapticd.Runtime", "includePlatforms": ["Linux"]}'))

# Hidden folders (Samples~) hold no .meta and need none; a file there is not an asset.
with tempfile.TemporaryDirectory() as temporary:
    copy = pathlib.Path(temporary) / package.name
    shutil.copytree(package, copy)
    (copy / "Samples~" / "Extra.cs").write_text("// a sample's script\n")
    (copy / ".hidden").write_text("x\n")
    status, output = run(copy)
    if status != 0:
        failures.append(f"a file in Samples~ or a hidden one was asked for a .meta:\n{output}")

for failure in failures:
    print("FAIL:", failure)
sys.exit(1 if failures else 0)
