"""Generates meshes/vm272_alt.msh from vm272_alt.geo (gmsh Python API, `pip install gmsh`)."""
import os
import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.option.setNumber("General.NumThreads", 1)
gmsh.open(os.path.join(HERE, "vm272_alt.geo"))
gmsh.model.mesh.generate(2)
gmsh.write(os.path.join(HERE, "vm272_alt.msh"))
print("gmsh", gmsh.__version__, "wrote vm272_alt.msh with", len(gmsh.model.mesh.getNodes()[0]), "nodes")
gmsh.finalize()
