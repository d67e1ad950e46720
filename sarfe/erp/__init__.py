"""sarfe.erp"""
