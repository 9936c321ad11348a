"""The plug-ins that ship with the package (SPEC §20): each contributes what is particular to one machine.

They are loaded by name through :mod:`mtmcal_bayes.machines.plugins` when a machine's description names them, never
imported by the package's layers; each imports what it contributes when asked for it.
"""
