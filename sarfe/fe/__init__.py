"""sarfe.fe"""
