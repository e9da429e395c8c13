"""MJCF files as MuJoCo reads them, made into one text Drake's MuJoCo parser reads, on a
copy, rewriting what Drake refuses or asserts on:

- ``<include file>``: replaced by the included ``<mujoco>``'s children (MuJoCo's paths).
- Meshes: resolved as MuJoCo does (meshdir, assetdir), non-OBJ converted to OBJ
  (robots.meshes.obj_of), an unnamed mesh named by its file's stem.
- An ``<inertial>`` of zero mass: dropped (a massless body, as in MuJoCo).
- A servo on a joint: a ``<motor>`` of its gear, its force range the effort limit.
- Thin-shell inertia (``shellinertia``) and vector attributes of the wrong count:
  refused, naming the element.

A joint's ``frictionloss`` and ``armature``, which Drake's parser does not take, are
read through the ``<default>`` classes. Errors name the file (and line) and element."""
import functools
from pathlib import Path
from typing import Dict, Iterator, List, Tuple
import xml.etree.ElementTree as ElementTree

import numpy as np

from dacph_drake.scenario.errors import ConfigError
from dacph_drake.robots.meshes import obj_of

# Mesh formats MuJoCo reads; .obj goes to Drake as it is.
MESH_SUFFIXES = (".stl", ".obj", ".msh")
# Includes nested deeper than this are a cycle.
MAX_INCLUDE_DEPTH = 16
# An element of a body, its attributes as MuJoCo resolves them, and its body (_Resolved).
_Resolution = Tuple[ElementTree.Element, Dict[str, str], ElementTree.Element]
# MuJoCo's actuators other than <motor> that act on a joint: servos (a force law of
# the joint's own state and ctrl) and <general>, which Drake's parser ignores.
SERVOS = ("position", "velocity", "intvelocity", "damper", "general")
# The vector attributes MuJoCo reads with a fixed count of numbers (gear: 1 to 6).
VECTOR_SIZES = {"pos": (3,), "quat": (4,), "euler": (3,), "axis": (3,),
                "axisangle": (4,), "xyaxes": (6,), "zaxis": (3,), "range": (2,),
                "diaginertia": (3,), "fullinertia": (6,), "fromto": (6,),
                "ctrlrange": (2,), "forcerange": (2,), "gear": tuple(range(1, 7))}


class MjcfFile:
    """One MJCF file, read once: ``drake_text`` (None when it needs no rewriting), its
    joints' resolved attributes (JointAttribute), ``servos`` (replaced by torque motors) and
    ``mesh_inertia_notes`` (_MeshInertiaNotes).

    Args:
        path: The MJCF file.

    Raises:
        ConfigError: A bad XML file, a non-MJCF root, a missing or cyclic include, a mesh
            missing or of a format MuJoCo does not read, naming the file and the element."""

    def __init__(self, path: Path):
        self.path = path
        self._root = _Parse(path)
        changed = _ExpandIncludes(self._root, path, path.parent, depth=0)
        _CheckVectors(self._root, path)
        _RefuseShellInertia(self._root, path)
        self.servos, rewritten = _ServosAsMotors(self._root)
        changed |= rewritten
        changed |= _ConvertMeshes(self._root, path)
        self.mesh_inertia_notes = _MeshInertiaNotes(self._root)
        changed |= _DropMasslessInertials(self._root)
        self.drake_text = (ElementTree.tostring(self._root, encoding="unicode")
                           if changed else None)

    def JointAttribute(self, attribute: str) -> Dict[str, float]:
        """Joint name -> its ``attribute`` (frictionloss [N m], armature [kg m^2]) where
        positive, as MuJoCo resolves it.

        Args:
            attribute: The joint attribute.

        Raises:
            ConfigError: A value that is not a number >= 0, naming the joint."""
        values = {}
        for joint, attributes, _ in _Resolved(self._root, "joint"):
            value = attributes.get(attribute, "0")
            number = nonnegative_number(value, f"{self.path}: joint "
                                        f"{joint.get('name', '(unnamed)')!r}: "
                                        f"{attribute}={value!r}")
            if number > 0 and joint.get("name"):
                values[joint.get("name")] = number
        return values


def _Classes(root: ElementTree.Element, tag: str) -> Dict[str, Dict[str, str]]:
    """Default class -> the attributes it gives a ``tag`` element (inherited by nesting)."""
    classes: Dict[str, Dict[str, str]] = {}

    def visit_default(default, inherited):
        attributes = dict(inherited)
        element = default.find(tag)
        if element is not None:
            attributes.update(element.attrib)
        classes[default.get("class", "main")] = attributes
        for child in default.findall("default"):
            visit_default(child, attributes)
    for default in root.findall("default"):
        visit_default(default, {})
    return classes


def _Resolved(root: ElementTree.Element, tag: str) -> Iterator[_Resolution]:
    """Each ``tag`` element of the bodies with its attributes as MuJoCo resolves them (own,
    else its class's, else the enclosing ``childclass``'s, else "main"), and its body."""
    classes = _Classes(root, tag)

    def visit_body(body, childclass):
        childclass = body.get("childclass", childclass)
        for element in body.findall(tag):
            yield element, {**classes.get(element.get("class", childclass), {}),
                            **element.attrib}, body
        for child in body.findall("body"):
            yield from visit_body(child, childclass)
    for world in root.findall("worldbody"):
        yield from visit_body(world, "main")


def _ServosAsMotors(root: ElementTree.Element) -> Tuple[List[str], bool]:
    """Replaces each servo on a joint (SERVOS) by a <motor> of its gear: the controller
    commands the joint's torque. The servo's force limit becomes the motor's ctrlrange
    (effort limit |gear| x forcerange); a <general> without bias keeps its ctrlrange, its
    gain in the gear. Returns (each servo replaced as "kind 'name' on joint 'j'", whether
    any actuator was rewritten)."""
    replaced, rewritten = [], False
    classes = {tag: _Classes(root, tag) for tag in SERVOS}
    for actuators in root.iter("actuator"):
        for index, element in enumerate(list(actuators)):
            if element.tag not in SERVOS or element.get("joint") is None:
                continue
            attributes = {**classes[element.tag].get(element.get("class", "main"), {}),
                          **element.attrib}
            joint = attributes["joint"]
            gear = float(attributes.get("gear", "1").split()[0])
            motor = ElementTree.Element("motor", {"joint": joint})
            if element.get("name"):
                motor.set("name", element.get("name"))
            torque = (element.tag == "general"
                      and attributes.get("biastype", "none") == "none"
                      and attributes.get("gaintype", "fixed") == "fixed")
            if torque:
                gear *= float(attributes.get("gainprm", "1").split()[0])
                limits = attributes.get("ctrlrange") if attributes.get(
                    "ctrllimited", "auto") != "false" else None
            else:
                replaced.append(f"{element.tag} {element.get('name', '(unnamed)')!r} on "
                                f"joint {joint!r}")
                limits = attributes.get("forcerange") if attributes.get(
                    "forcelimited", "auto") != "false" else None
            motor.set("gear", repr(gear))
            if limits is not None:
                motor.set("ctrlrange", limits)
                motor.set("ctrllimited", "true")
            else:
                motor.set("ctrllimited", "false")
            actuators.remove(element)
            actuators.insert(index, motor)
            rewritten = True
    return replaced, rewritten


def _InertiaGeoms(root: ElementTree.Element) -> Iterator[_Resolution]:
    """The geoms whose inertia gives their body's (_Resolved's triples): all of a body
    without an <inertial> (compiler inertiafromgeom "auto"), or of every body ("true")."""
    from_geoms = "auto"
    for compiler in root.iter("compiler"):
        from_geoms = compiler.get("inertiafromgeom", from_geoms)
    for geom, attributes, body in _Resolved(root, "geom"):
        if from_geoms == "true" or (from_geoms == "auto"
                                    and body.find("inertial") is None):
            yield geom, attributes, body


def _RefuseShellInertia(root: ElementTree.Element, path: Path) -> None:
    """Refuses a geom whose inertia MuJoCo takes as a thin shell where the geoms give the
    body's inertia: Drake's parser would take the solid's."""
    for geom, attributes, body in _InertiaGeoms(root):
        if attributes.get("shellinertia", "false") == "true":
            raise ConfigError(
                f"{path}: geom {geom.get('name', '(unnamed)')!r} of body "
                f"{body.get('name', '(unnamed)')!r}: shellinertia='true' (MuJoCo's thin-"
                "shell inertia) is not modelled; allowed: a solid geom, or an <inertial> "
                "on the body")


def nonnegative_number(value: str, named: str) -> float:
    """A description's attribute as a finite number >= 0.

    Args:
        value: The attribute's text.
        named: The file, element and attribute, for the message.

    Raises:
        ConfigError: "{named}; allowed: a number >= 0"."""
    try:
        number = float(value)
    except ValueError:
        number = -1.0
    if not (np.isfinite(number) and number >= 0):
        raise ConfigError(f"{named}; allowed: a number >= 0")
    return number


def _Parse(path: Path, included: bool = False) -> ElementTree.Element:
    """The file's root element: <mujoco>, or for an included file <mujocoinclude>."""
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError as e:
        raise ConfigError(f"{path}:{e.position[0]}: not an XML file ({e}); allowed: "
                          "an MJCF file") from e
    except OSError as e:
        raise ConfigError(f"{path}: cannot be read ({e.strerror})") from e
    roots = ("mujoco", "mujocoinclude") if included else ("mujoco",)
    if root.tag not in roots:
        raise ConfigError(f"{path}: its root element is <{root.tag}>; allowed: an MJCF "
                          f"file, whose root is {' or '.join(f'<{r}>' for r in roots)}")
    return root


def _ExpandIncludes(element: ElementTree.Element, path: Path, main: Path,
                    depth: int) -> bool:
    """Replaces each <include> below ``element`` by its file's children; whether any."""
    changed = False
    for index, child in reversed(list(enumerate(element))):
        if child.tag != "include":
            changed |= _ExpandIncludes(child, path, main, depth)
            continue
        name = child.get("file")
        if not name:
            raise ConfigError(f"{path}: an <include> without a file attribute; allowed: "
                              "<include file=\"...\"/>")
        if depth >= MAX_INCLUDE_DEPTH:
            raise ConfigError(f"{path}: <include file={name!r}> nests more than "
                              f"{MAX_INCLUDE_DEPTH} deep (a cycle?); allowed: includes "
                              "that end")
        candidates = [Path(name)] if Path(name).is_absolute() else [main / name,
                                                                     path.parent / name]
        found = next((c for c in candidates if c.is_file()), None)
        if found is None:
            raise ConfigError(f"{path}: <include file={name!r}>: no such file (looked "
                              f"in {main}); allowed: a path relative to the main "
                              "file's folder")
        included = _Parse(found, included=True)
        _ExpandIncludes(included, found, main, depth + 1)
        element.remove(child)
        for offset, part in enumerate(list(included)):
            element.insert(index + offset, part)
        changed = True
    return changed


def _AssetFolder(root: ElementTree.Element, path: Path, kind: str) -> Path:
    """The folder of a kind's assets: compiler KINDdir, else assetdir, else main's."""
    folder = None
    for compiler in root.iter("compiler"):
        folder = compiler.get(f"{kind}dir") or compiler.get("assetdir") or folder
    if folder is None:
        return path.parent
    return Path(folder) if Path(folder).is_absolute() else path.parent / folder


def _ConvertMeshes(root: ElementTree.Element, path: Path) -> bool:
    """Points every <mesh file> at an absolute .obj (converted where needed) named as MuJoCo
    would, every <texture file> at its absolute path; whether any mesh was seen."""
    folder = _AssetFolder(root, path, "mesh")
    textures = _AssetFolder(root, path, "texture")
    for texture in root.iter("texture"):
        if texture.get("file") and not Path(texture.get("file")).is_absolute():
            texture.set("file", str((textures / texture.get("file")).resolve()))
    meshes = [mesh for asset in root.iter("asset") for mesh in asset.iter("mesh")
              if mesh.get("file")]
    for mesh in meshes:
        name = mesh.get("file")
        if mesh.get("name") is None:
            mesh.set("name", Path(name).stem)
        source = Path(name) if Path(name).is_absolute() else folder / name
        suffix = source.suffix.lower()
        if suffix not in MESH_SUFFIXES:
            raise ConfigError(f"{path}: mesh {mesh.get('name')!r} file {name!r} "
                              f"is a {suffix or 'suffix-less'} file; allowed: "
                              f"{', '.join(MESH_SUFFIXES)} (the formats MuJoCo reads)")
        if not source.is_file():
            raise ConfigError(f"{path}: mesh {mesh.get('name')!r}: no such file "
                              f"{str(source)!r} (compiler meshdir/assetdir: "
                              f"{folder}); allowed: an existing mesh file")
        mesh.set("file", str(source.resolve() if suffix == ".obj" else obj_of(source)))
    for compiler in root.iter("compiler"):
        for attribute in ("meshdir", "texturedir", "assetdir"):
            compiler.attrib.pop(attribute, None)
    return bool(meshes)


def _CheckVectors(root: ElementTree.Element, path: Path) -> None:
    """Refuses a vector attribute (VECTOR_SIZES) not of its count of finite numbers."""
    for element in root.iter():
        for attribute, sizes in VECTOR_SIZES.items():
            value = element.get(attribute)
            if value is None:
                continue
            try:
                numbers = [float(x) for x in value.split()]
            except ValueError:
                numbers = [np.nan]
            if len(numbers) not in sizes or not np.all(np.isfinite(numbers)):
                name = element.get("name")
                named = f" name={name!r}" if name else ""
                count = (f"{sizes[0]}" if len(sizes) == 1
                         else f"{sizes[0]} to {sizes[-1]}")
                raise ConfigError(f"{path}: <{element.tag}{named}> {attribute}={value!r}; "
                                  f"allowed: {count} finite numbers")


def _MeshInertiaNotes(root: ElementTree.Element) -> List[str]:
    """The meshes whose inertia MuJoCo ("legacy": each face's pyramid counted positive;
    "convex": the hull) takes otherwise than Drake's exact volume, where it gives their
    body's: "mesh 'name' (legacy: volume V, exact V_e)"."""
    meshes = {}
    classes = _Classes(root, "mesh")
    for asset in root.iter("asset"):
        for mesh in asset.iter("mesh"):
            if mesh.get("file"):
                meshes[mesh.get("name")] = {**classes.get(mesh.get("class", "main"), {}),
                                            **mesh.attrib}
    notes = set()
    for geom, attributes, body in _InertiaGeoms(root):
        mesh = meshes.get(attributes.get("mesh")) if attributes.get("type") == "mesh" \
            else None
        mode = None if mesh is None else mesh.get("inertia", "legacy")
        if mode not in ("legacy", "convex") or float(attributes.get(
                "mass", attributes.get("density", "1000"))) <= 0:
            continue
        volume, exact = _MujocoVolumes(mesh["file"], Path(mesh["file"]).stat().st_mtime_ns,
                                       mesh.get("scale", "1 1 1"), mode)
        if abs(volume - exact) > 1e-6 * abs(exact):
            notes.add(f"mesh {attributes['mesh']!r} ({mode}: volume {volume:.4g} m^3, "
                      f"exact {exact:.4g})")
    return sorted(notes)


@functools.lru_cache(maxsize=None)
def _MujocoVolumes(obj: str, modified: int, scale: str, mode: str) -> Tuple[float, float]:
    """(MuJoCo's volume in inertia mode ``mode``, exact volume) of OBJ ``obj`` scaled by
    ``scale``, from pyramids on each face with apex at the area-weighted centroid (MuJoCo's
    ComputeVolume); cached by (path, ``modified`` ns)."""
    import trimesh
    loaded = trimesh.load(obj, force="mesh", process=False)
    vertices = np.asarray(loaded.vertices) * [float(x) for x in scale.split()]
    faces = np.asarray(loaded.faces)

    def pyramids(vertices, faces):
        triangles = vertices[faces]
        cross = np.cross(triangles[:, 1] - triangles[:, 0],
                         triangles[:, 2] - triangles[:, 0])
        area = 0.5 * np.linalg.norm(cross, axis=1)
        center = triangles.mean(axis=1)
        apex = (area[:, None] * center).sum(axis=0) / area.sum()
        return np.einsum("ij,ij->i", center - apex, cross) / 6.0   # (c - a) . n area / 3
    signed = pyramids(vertices, faces)
    if mode == "convex":
        hull = trimesh.Trimesh(vertices, faces, process=False).convex_hull
        return float(pyramids(np.asarray(hull.vertices), np.asarray(hull.faces)).sum()), \
            float(signed.sum())
    return float(np.abs(signed).sum()), float(signed.sum())


def _DropMasslessInertials(root: ElementTree.Element) -> bool:
    """Removes every body's <inertial> of zero mass; whether any was removed."""
    changed = False
    for body in root.iter("body"):
        for inertial in body.findall("inertial"):
            mass = inertial.get("mass", "1")
            try:
                massless = float(mass) == 0.0
            except ValueError:
                raise ConfigError(f"body {body.get('name', '(unnamed)')!r}: <inertial "
                                  f"mass={mass!r}>; allowed: a number >= 0") from None
            if massless:
                body.remove(inertial)
                changed = True
    return changed
