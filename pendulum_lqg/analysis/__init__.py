"""Analysis beside the simulation: margins, region of attraction, the studies, the report and its figures.

================  ========================================================================
module            concept
================  ========================================================================
``margins``       loop gains, stability margins and loop transfer recovery (pure functions of matrices)
``roa``           the region of attraction of a policy, measured through the one closed loop
``studies``       the studies that are not plain grids (``study = "margins"`` / ``"roa"``)
``reading``       reading a results folder for the report, field by field
``report``        ``pendulum-lqg report RESULTS…``: a Markdown report with PNG figures
``figures``       the report's figures and tables, one function per kind of study
``episode_plot``  a static figure of one episode (``run --plot``): states, estimates, y, u
================  ========================================================================
"""
