"""sarfe.hbm"""
