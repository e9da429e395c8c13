"""Meshes as robot packages ship them, for Drake's SceneGraph: a collision mesh must
be .obj, .vtk or .gltf (SceneGraph takes its convex hull), while URDFs from ROS
packages (example-robot-data's Panda, Universal Robots' arms) give STL. The rule:
every STL mesh a URDF names is converted, triangle for triangle, to an OBJ in a
cache folder (named by the STL's content hash), and the URDF is read with those
names; the convex hull SceneGraph then takes is the STL's. Other meshes are left as
they are (their relative paths made absolute file:// URIs)."""
import hashlib
import re
import tempfile
from pathlib import Path
from typing import Optional

import numpy as np

from dacph_drake.errors import ConfigError

CACHE = Path(tempfile.gettempdir()) / "dacph_drake_meshes"
_MESH = re.compile(r'(<mesh\s[^>]*filename\s*=\s*")([^"]+)(")')


def urdf_with_obj_meshes(path: Path, package_map) -> Optional[str]:
    """The URDF text of ``path`` with its STL meshes replaced by converted OBJs and
    its relative mesh paths made absolute, or None when it names no STL mesh."""
    text = path.read_text(encoding="utf-8")
    if not any(name.lower().endswith(".stl") for _, name, _ in _MESH.findall(text)):
        return None

    def replace(match):
        name = match.group(2)
        if name.lower().endswith(".stl"):
            name = "file://" + str(_ObjOf(_Resolve(name, path, package_map)))
        elif "://" not in name:          # a string's URIs have no folder of their own
            name = "file://" + str((path.parent / name).resolve())
        return match.group(1) + name + match.group(3)
    return _MESH.sub(replace, text)


def _Resolve(name: str, path: Path, package_map) -> Path:
    """The file a URDF mesh name stands for (package://, file:// or relative)."""
    if name.startswith("package://"):
        package, _, rest = name[len("package://"):].partition("/")
        if not package_map.Contains(package):
            raise ConfigError(f"{path}: mesh {name!r} refers to unknown package "
                              f"{package!r}; allowed: a package on robot.package_paths, "
                              "robot.packages or ROS_PACKAGE_PATH")
        return Path(package_map.GetPath(package)) / rest
    if name.startswith("file://"):
        return Path(name[len("file://"):])
    return path.parent / name


def _ObjOf(stl: Path) -> Path:
    """The cached OBJ of an STL file (ConfigError naming a missing or bad file)."""
    try:
        data = stl.read_bytes()
    except OSError as e:
        raise ConfigError(f"mesh {str(stl)!r} cannot be read ({e.strerror})") from e
    obj = CACHE / f"{hashlib.sha256(data).hexdigest()[:20]}.obj"
    if not obj.is_file():
        triangles = stl_triangles(data, stl)
        CACHE.mkdir(parents=True, exist_ok=True)
        lines = [f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in triangles.reshape(-1, 3)]
        lines += [f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}" for k in range(len(triangles))]
        partial = obj.with_suffix(f".{hashlib.sha256(str(stl).encode()).hexdigest()[:8]}")
        partial.write_text("\n".join(lines) + "\n")
        partial.replace(obj)                # atomic: concurrent workers agree
    return obj


def stl_triangles(data: bytes, name) -> np.ndarray:
    """The triangles (k, 3 vertices, xyz) of an STL file's bytes, binary or ASCII."""
    if len(data) >= 84:
        count = int(np.frombuffer(data[80:84], "<u4")[0])
        if len(data) == 84 + 50 * count:                   # binary
            records = np.frombuffer(data[84:], np.dtype([("normal", "<f4", 3),
                                                         ("vertices", "<f4", (3, 3)),
                                                         ("attribute", "<u2")]))
            return records["vertices"].astype(float)
    vertices = re.findall(rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)", data)
    if not vertices or len(vertices) % 3:
        raise ConfigError(f"mesh {str(name)!r} is not an STL file; allowed: binary or "
                          "ASCII STL")
    return np.array(vertices, dtype=float).reshape(-1, 3, 3)
