"""sarfe.io"""
