"""sarfe.reduction"""
