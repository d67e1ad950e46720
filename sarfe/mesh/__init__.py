"""sarfe.mesh"""
