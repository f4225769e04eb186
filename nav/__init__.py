"""nav: the shared ZUPT-aided navigation filter.

Reads any recording (simulated or measured) and never imports the simulator (``gaitsim``).
"""
