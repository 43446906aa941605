"""Small services every layer uses: ceilings, files, JSON, progress, resources, scripts.

=============  ========================================================================
module         concept
=============  ========================================================================
``limits``     the documented ceilings that keep a run finite in memory and time
``files``      the one output rule: atomic writes, only new paths or regular files replaced
``jsonio``     one JSON-ready conversion for results (arrays, complex, non-finite floats)
``progress``   progress of a long command, on stderr only
``resources``  the data files the package ships: cart-pole models and experiment files
``scripts``    the command-line contract of the project's scripts (``benchmarks/*.py``)
``watchdog``   a time limit on user code (a plug-in or agent call)
=============  ========================================================================
"""
