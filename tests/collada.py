"""COLLADA documents written by the tests: triangle meshes, placed as the exporters place them."""

from __future__ import annotations


def _geometry(gid: str, vertices, faces, name: str = "") -> str:
    """One <geometry> of a triangle mesh (``vertices`` (x, y, z), ``faces`` (a, b, c))."""
    positions = " ".join(f"{float(v):.9g}" for corner in vertices for v in corner)
    indices = " ".join(str(int(i)) for face in faces for i in face)
    named = f' name="{name}"' if name else ""
    return f"""<geometry id="{gid}"{named}><mesh>
    <source id="{gid}p"><float_array id="{gid}pa" count="{3 * len(vertices)}">{positions}</float_array>
      <technique_common><accessor source="#{gid}pa" count="{len(vertices)}" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="{gid}v"><input semantic="POSITION" source="#{gid}p"/></vertices>
    <triangles count="{len(faces)}"><input semantic="VERTEX" source="#{gid}v" offset="0"/><p>{indices}</p></triangles>
  </mesh></geometry>"""


def _document(geometries: str, nodes: str, scene: str, meter: float) -> str:
    return f"""<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="{meter}" name="unit"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>{geometries}</library_geometries>
  {nodes}
  <library_visual_scenes><visual_scene id="s">{scene}</visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""


def collada(vertices, faces, meter: float = 1.0, matrix: str | None = None, instanced: bool = False) -> str:
    """A COLLADA document of one mesh (``vertices`` (x, y, z), ``faces`` (a, b, c)) in units of
    ``meter`` metres, its node placed by ``matrix`` (16 numbers, row major) or, ``instanced``,
    through <library_nodes> and <instance_node> as Onshape exports (which PyBullet cannot read)."""
    transform = f"<matrix>{matrix}</matrix>" if matrix else ""
    if instanced:
        nodes = '<library_nodes><node id="inner"><instance_geometry url="#g"/></node></library_nodes>'
        placed = f'<node id="n">{transform}<instance_node url="#inner"/></node>'
    else:
        nodes, placed = "", f'<node id="n">{transform}<instance_geometry url="#g"/></node>'
    return _document(_geometry("g", vertices, faces), nodes, placed, meter)


def collada_parts(parts: dict, meter: float = 1.0) -> str:
    """A COLLADA document of named meshes, each {name: (vertices, faces, matrix or None)}: a
    <geometry name=NAME> under a <node name=NAME> placed by the matrix (16 numbers, row major),
    as a model's parts are exported (an SDF <submesh> names one)."""
    geometries, nodes = [], []
    for i, (name, (vertices, faces, matrix)) in enumerate(parts.items()):
        geometries.append(_geometry(f"g{i}", vertices, faces, name))
        transform = f"<matrix>{matrix}</matrix>" if matrix else ""
        nodes.append(f'<node id="n{i}" name="{name}">{transform}<instance_geometry url="#g{i}"/></node>')
    return _document("".join(geometries), "", "".join(nodes), meter)
