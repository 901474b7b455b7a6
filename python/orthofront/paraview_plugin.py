"""Loads the ParaView filters of orthofront (paraview/orthofront_filters.py beside this package)
into pvpython, pvbatch or the ParaView GUI's Python shell:

    import orthofront.paraview_plugin
    orthofront.paraview_plugin.load(globals())

Debian's ParaView 5.11 cannot load Python plugins under Python 3.11 as shipped (its
paraview.detail.pythonalgorithm imports inspect.getargspec, removed in 3.11); load() supplies
that function first, so the filters load there too.
"""

import inspect
import os

PLUGIN = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "paraview",
                      "orthofront_filters.py")


def _supply_getargspec():
    if not hasattr(inspect, "getargspec"):
        # Only .args is used: the number of values a property setter takes.
        inspect.getargspec = inspect.getfullargspec


def load(ns=None):
    """Loads the plugin; its filters become functions of `ns` (e.g. globals()) as with
    paraview.simple.LoadPlugin. Returns the plugin's path."""
    _supply_getargspec()
    from paraview.simple import LoadPlugin
    if not os.path.isfile(PLUGIN):
        raise FileNotFoundError("%s: the ParaView plugin is not where the build puts it" % PLUGIN)
    LoadPlugin(PLUGIN, ns=ns)
    return PLUGIN
