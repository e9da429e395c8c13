"""Meshes as robot packages ship them, for Drake's SceneGraph, whose collision meshes must
be .obj, .vtk or .gltf: every STL a URDF names, and every .dae of a <collision>, is
converted triangle for triangle to a cached OBJ (by content hash), so the hull is the
original's. A .dae's triangles are placed by the <visual_scene>'s nodes in document
order, in metres (<up_axis> not applied, as ROS's tools do). Other meshes stay as they
are (paths made absolute file:// URIs)."""
import hashlib
import io
import re
import tempfile
from pathlib import Path
from typing import Optional, Union

import numpy as np
from pydrake.multibody.parsing import PackageMap

from dacph_drake.scenario.errors import ConfigError

CACHE = Path(tempfile.gettempdir()) / "dacph_drake_meshes"
_MESH = re.compile(r'(<mesh\s[^>]*filename\s*=\s*")([^"]+)(")')
_COLLISION = re.compile(r"<collision\b.*?</collision>", re.S)


def urdf_with_obj_meshes(path: Path, package_map: PackageMap,
                         text: Optional[str] = None) -> Optional[str]:
    """A URDF's text with its meshes converted, or None when there is nothing to change.

    Args:
        path: The URDF file.
        package_map: Resolves its package:// mesh URIs.
        text: The file's text as read so far (default: the file's).

    Raises:
        ConfigError: A mesh names an unknown package, or cannot be read or converted."""
    original = path.read_text(encoding="utf-8")
    text = original if text is None else text
    collision = [match.span() for match in _COLLISION.finditer(text)]

    def converted(match) -> bool:
        suffix = Path(match.group(2)).suffix.lower()
        return suffix == ".stl" or (suffix == ".dae" and any(
            start <= match.start() < end for start, end in collision))
    if text == original and not any(converted(match) for match in _MESH.finditer(text)):
        return None

    def replace(match):
        name = match.group(2)
        if converted(match):
            name = "file://" + str(obj_of(_Resolve(name, path, package_map)))
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


def obj_of(mesh: Path) -> Path:
    """The cached OBJ of an STL, .dae or MuJoCo .msh file (ConfigError naming a bad one).

    Args:
        mesh: The mesh file."""
    try:
        data = mesh.read_bytes()
    except OSError as e:
        raise ConfigError(f"mesh {str(mesh)!r} cannot be read ({e.strerror})") from e
    obj = CACHE / f"{hashlib.sha256(data).hexdigest()[:20]}.obj"
    if not obj.is_file():
        read = {".dae": dae_triangles, ".msh": msh_triangles}.get(mesh.suffix.lower(),
                                                                  stl_triangles)
        triangles = read(data, mesh)
        CACHE.mkdir(parents=True, exist_ok=True)
        lines = [f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in triangles.reshape(-1, 3)]
        lines += [f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}" for k in range(len(triangles))]
        partial = obj.with_suffix(f".{hashlib.sha256(str(mesh).encode()).hexdigest()[:8]}")
        partial.write_text("\n".join(lines) + "\n")
        partial.replace(obj)                # atomic: concurrent workers agree
    return obj


def stl_triangles(data: bytes, name: Union[str, Path]) -> np.ndarray:
    """The triangles (k, 3 vertices, xyz) of an STL file's bytes, binary or ASCII (trimesh).

    Args:
        data: The file's bytes.
        name: The file's name, for the error message.

    Raises:
        ConfigError: The bytes are not an STL file."""
    import trimesh
    try:
        mesh = trimesh.load(io.BytesIO(data), file_type="stl", process=False)
        triangles = (np.asarray(mesh.triangles, float) if len(mesh.faces)
                     else np.zeros((0, 3, 3)))
    except Exception as e:               # trimesh raises what its readers raise
        raise ConfigError(f"mesh {str(name)!r} is not an STL file ({type(e).__name__}: "
                          f"{e}); allowed: binary or ASCII STL") from None
    if not len(triangles):
        raise ConfigError(f"mesh {str(name)!r} is not an STL file with triangles; "
                          "allowed: binary or ASCII STL")
    return triangles


def msh_triangles(data: bytes, name: Union[str, Path]) -> np.ndarray:
    """The triangles (k, 3, xyz) of MuJoCo's legacy binary .msh: int32 counts, then float32
    positions (3), normals (3), texture coordinates (2) and int32 faces (3).

    Args:
        data: The file's bytes.
        name: The file's name, for the error message.

    Raises:
        ConfigError: The bytes are not a .msh file."""
    if len(data) >= 16:
        vertices, normals, textures, faces = np.frombuffer(data[:16], "<i4")
        sizes = (3 * vertices, 3 * normals, 2 * textures, 3 * faces)
        if min(sizes) >= 0 and vertices > 0 and faces > 0 and \
                len(data) == 16 + 4 * sum(sizes):
            floats = np.frombuffer(data[16:16 + 4 * sum(sizes[:3])], "<f4")
            index = np.frombuffer(data[16 + 4 * sum(sizes[:3]):], "<i4").reshape(-1, 3)
            if index.min() >= 0 and index.max() < vertices:
                return floats[:sizes[0]].astype(float).reshape(-1, 3)[index]
    raise ConfigError(f"mesh {str(name)!r} is not a MuJoCo .msh file (its counts and "
                      "size disagree); allowed: MuJoCo's binary .msh, STL or OBJ")


def dae_triangles(data: bytes, name: Union[str, Path]) -> np.ndarray:
    """The triangles (k, 3 vertices, xyz) [m] of a Collada file's bytes (module docstring).

    Args:
        data: The file's bytes.
        name: The file's name, for the error message.

    Raises:
        ConfigError: The bytes are not a Collada file, or hold no triangles."""
    import xml.etree.ElementTree as ElementTree
    try:
        root = ElementTree.fromstring(data)
    except ElementTree.ParseError as e:
        raise ConfigError(f"mesh {str(name)!r} is not a Collada file ({e}); allowed: "
                          "Collada .dae") from e
    for element in root.iter():                      # drop the namespace
        element.tag = element.tag.rpartition("}")[2]
    unit = root.find("asset/unit")
    scale = float(unit.get("meter", "1")) if unit is not None else 1.0
    geometries = {g.get("id"): _GeometryTriangles(g) for g in root.iter("geometry")}
    placed = []
    scene = root.find("library_visual_scenes/visual_scene")
    if scene is None:
        placed = list(geometries.values())
    else:
        def visit(node, X):
            X = X @ _NodeTransform(node)
            for instance in node.findall("instance_geometry"):
                triangles = geometries.get(instance.get("url", "").lstrip("#"))
                if triangles is not None and len(triangles):
                    points = triangles.reshape(-1, 3) @ X[:3, :3].T + X[:3, 3]
                    placed.append(points.reshape(-1, 3, 3))
            for child in node.findall("node"):
                visit(child, X)
        for node in scene.findall("node"):
            visit(node, np.eye(4))
    if not placed or not sum(len(t) for t in placed):
        raise ConfigError(f"mesh {str(name)!r} has no triangles; allowed: a Collada "
                          "file with triangles, polylist or polygons")
    return np.concatenate(placed) * scale


def _GeometryTriangles(geometry) -> np.ndarray:
    """The triangles of a <geometry>'s <mesh> in its own frame (polygons fanned)."""
    mesh = geometry.find("mesh")
    if mesh is None:
        return np.zeros((0, 3, 3))
    sources = {s.get("id"): np.array((s.findtext("float_array") or "").split(), float)
               for s in mesh.findall("source")}
    vertices = {}
    for element in mesh.findall("vertices"):
        for put in element.findall("input"):
            if put.get("semantic") == "POSITION":
                vertices[element.get("id")] = sources[put.get("source").lstrip("#")]
    out = []
    for primitive in [*mesh.findall("triangles"), *mesh.findall("polylist"),
                      *mesh.findall("polygons")]:
        inputs = primitive.findall("input")
        stride = 1 + max(int(i.get("offset", 0)) for i in inputs)
        vertex = next(i for i in inputs if i.get("semantic") == "VERTEX")
        positions = vertices[vertex.get("source").lstrip("#")].reshape(-1, 3)
        offset = int(vertex.get("offset", 0))
        lists = [p.text or "" for p in primitive.findall("p")]
        if primitive.tag == "triangles":
            counts = None
        elif primitive.tag == "polylist":
            counts = np.array((primitive.findtext("vcount") or "").split(), int)
        else:                                            # polygons: one <p> each
            counts = np.array([len(text.split()) // stride for text in lists], int)
        index = np.array(" ".join(lists).split(), int)[offset::stride]
        if counts is None:
            out.append(positions[index.reshape(-1, 3)])
            continue
        start = 0
        for count in counts:
            polygon = index[start:start + count]
            start += count
            out += [positions[[polygon[0], polygon[k], polygon[k + 1]]][None]
                    for k in range(1, count - 1)]
    return np.concatenate(out) if out else np.zeros((0, 3, 3))


def _NodeTransform(node) -> np.ndarray:
    """The 4x4 transform of a <node>'s matrix, translate, rotate, scale (in order)."""
    X = np.eye(4)
    for element in node:
        values = np.array((element.text or "").split(), float)
        step = np.eye(4)
        if element.tag == "matrix":
            step = values.reshape(4, 4)
        elif element.tag == "translate":
            step[:3, 3] = values
        elif element.tag == "scale":
            step[:3, :3] = np.diag(values)
        elif element.tag == "rotate":
            axis, angle = values[:3] / np.linalg.norm(values[:3]), np.radians(values[3])
            K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]],
                          [-axis[1], axis[0], 0]])
            step[:3, :3] = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K
        else:
            continue
        X = X @ step
    return X
