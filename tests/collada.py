"""COLLADA documents written by the tests: one triangle mesh, placed as the exporters place it."""

from __future__ import annotations


def collada(vertices, faces, meter: float = 1.0, matrix: str | None = None, instanced: bool = False) -> str:
    """A COLLADA document of one mesh (``vertices`` (x, y, z), ``faces`` (a, b, c)) in units of
    ``meter`` metres, its node placed by ``matrix`` (16 numbers, row major) or, ``instanced``,
    through <library_nodes> and <instance_node> as Onshape exports (which PyBullet cannot read)."""
    positions = " ".join(f"{float(v):.9g}" for corner in vertices for v in corner)
    indices = " ".join(str(int(i)) for face in faces for i in face)
    transform = f"<matrix>{matrix}</matrix>" if matrix else ""
    if instanced:
        nodes = '<library_nodes><node id="inner"><instance_geometry url="#g"/></node></library_nodes>'
        placed = f'<node id="n">{transform}<instance_node url="#inner"/></node>'
    else:
        nodes, placed = "", f'<node id="n">{transform}<instance_geometry url="#g"/></node>'
    return f"""<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="{meter}" name="unit"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="{3 * len(vertices)}">{positions}</float_array>
      <technique_common><accessor source="#pa" count="{len(vertices)}" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="{len(faces)}"><input semantic="VERTEX" source="#v" offset="0"/><p>{indices}</p></triangles>
  </mesh></geometry></library_geometries>
  {nodes}
  <library_visual_scenes><visual_scene id="s">{placed}</visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""


def collada_parts(parts: dict, meter: float = 1.0) -> str:
    """A COLLADA document of named meshes, each {name: (vertices, faces, matrix or None)}: a
    <geometry name=NAME> under a <node name=NAME> placed by the matrix (16 numbers, row major),
    as a model's parts are exported (an SDF <submesh> names one)."""
    geometries, nodes = [], []
    for i, (name, (vertices, faces, matrix)) in enumerate(parts.items()):
        positions = " ".join(f"{float(v):.9g}" for corner in vertices for v in corner)
        indices = " ".join(str(int(k)) for face in faces for k in face)
        geometries.append(f"""<geometry id="g{i}" name="{name}"><mesh>
    <source id="p{i}"><float_array id="pa{i}" count="{3 * len(vertices)}">{positions}</float_array>
      <technique_common><accessor source="#pa{i}" count="{len(vertices)}" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v{i}"><input semantic="POSITION" source="#p{i}"/></vertices>
    <triangles count="{len(faces)}"><input semantic="VERTEX" source="#v{i}" offset="0"/><p>{indices}</p></triangles>
  </mesh></geometry>""")
        transform = f"<matrix>{matrix}</matrix>" if matrix else ""
        nodes.append(f'<node id="n{i}" name="{name}">{transform}<instance_geometry url="#g{i}"/></node>')
    return f"""<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="{meter}" name="unit"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries>{"".join(geometries)}</library_geometries>
  <library_visual_scenes><visual_scene id="s">{"".join(nodes)}</visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""
