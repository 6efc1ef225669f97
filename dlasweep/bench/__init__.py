"""The benchmark: growth and analysis timings, the host's memory probe, their targets and chart."""
