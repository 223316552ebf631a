"""Skills: controllers ticked by the world loop, each publishing its parameter schema.

`registry.py` is the mechanism (skills by name); `catalog.py` says which skills a robot offers.
"""
