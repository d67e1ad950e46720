"""sarfe.mesh.generators"""
