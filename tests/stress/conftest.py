"""The stress suite: bounded in time.  CI runs its reduced form; ``USARSIM_STRESS=full``
runs it at the sizes the README states (hundreds of thousands of fuzzed lines, 1,000
connect cycles, 500,000 DRIVE lines beside 63 robots)."""
