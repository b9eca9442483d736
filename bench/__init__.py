"""bt_nav benchmarks: ``python -m bench.run`` (``make bench``); see bench/run.py."""
