#!/usr/bin/python3
"""The Unity package as Unity's package manager takes it (scripts/unity-package check): the
package itself passes; and a copy broken in each way Unity would refuse or ignore fails, naming
what is wrong, so the check is known to catch each. Its tarball (scripts/unity-package pack) holds
every file under package/, the same bytes twice, and the files npm pack would put in one (when
npm is here to ask).
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

# The sample scene, broken as Unity would fail to load it or drop part of it silently.
scene = "Samples~/TouchWall/TouchWall.unity"


def edit_scene(copy, old, new):
    path = copy / scene
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new, 1))


broken("a scene referring to an object it lacks", "which the scene lacks",
       lambda c: edit_scene(c, "follower: {fileID: 304}", "follower: {fileID: 999}"))
broken("a scene's script that is not in the package", "which no .cs.meta of the package has",
       lambda c: (c / "Samples~" / "TouchWall" / "TouchWallScene.cs.meta").unlink())
broken("a scene setting a field its script lacks", "has no public field of",
       lambda c: edit_scene(c, "unitsPerMeter: 10", "metersPerUnit: 10"))
broken("a component that does not name its GameObject back", "does not name it back",
       lambda c: edit_scene(c, "m_GameObject: {fileID: 300}\n  m_Mesh", "m_GameObject: {fileID: 400}\n  m_Mesh"))

# Hidden folders (Samples~) hold no .meta and need none; a file there is not an asset.
with tempfile.TemporaryDirectory() as temporary:
    copy = pathlib.Path(temporary) / package.name
    shutil.copytree(package, copy)
    (copy / "Samples~" / "Extra.cs").write_text("// a sample's script\n")
    (copy / ".hidden").write_text("x\n")
    status, output = run(copy)
    if status != 0:
        failures.append(f"a file in Samples~ or a hidden one was asked for a .meta:\n{output}")

# The tarball: every file of the package under package/, made twice to the same bytes; and, where
# npm is here, the very files `npm pack` would put in (its dry run lists them).
import tarfile  # noqa: E402
with tempfile.TemporaryDirectory() as temporary:
    made = []
    for attempt in ("a", "b"):
        folder = pathlib.Path(temporary) / attempt
        folder.mkdir()
        result = subprocess.run([sys.executable, str(tool), "pack", str(package), str(folder)],
                                capture_output=True, text=True, timeout=60)
        if result.returncode != 0:
            failures.append(f"pack failed: {result.stdout}{result.stderr}")
            break
        made.extend(folder.glob("*.tgz"))
    if len(made) == 2:
        version = json.loads((package / "package.json").read_text())["version"]
        if made[0].name != f"com.hapticd.client-{version}.tgz":
            failures.append(f"the tarball is named {made[0].name}")
        if made[0].read_bytes() != made[1].read_bytes():
            failures.append("two packs of the same files differ")
        with tarfile.open(made[0]) as tar:
            names = sorted(tar.getnames())
        expected = sorted("package/" + p.relative_to(package).as_posix()
                          for p in package.rglob("*") if p.is_file())
        if names != expected:
            failures.append(f"the tarball holds {names}, not the package's files {expected}")
        for needed in ("package/package.json", "package/Runtime/Client.cs.meta",
                       "package/Samples~/TouchWall/TouchWallScene.cs"):
            if needed not in names:
                failures.append(f"the tarball lacks {needed}")
        npm = shutil.which("npm")
        if npm:
            dry = subprocess.run([npm, "pack", "--dry-run", "--json", "--ignore-scripts"], cwd=package,
                                 capture_output=True, text=True, timeout=120)
            if dry.returncode == 0:
                listed = sorted("package/" + f["path"] for f in json.loads(dry.stdout)[0]["files"])
                if listed != names:
                    failures.append(f"npm pack would pack {listed}, the tarball holds {names}")
                else:
                    print(f"the tarball holds the {len(names)} files npm pack would")
            else:
                print(f"npm pack --dry-run failed, not compared: {dry.stderr.strip()}")
        print(f"packed {made[0].name}: {len(names)} files, {made[0].stat().st_size} bytes")

for failure in failures:
    print("FAIL:", failure)
sys.exit(1 if failures else 0)
