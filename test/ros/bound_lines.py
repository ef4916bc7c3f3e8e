"""The checks of a measured figure in the Python rostests, each printed as one line that
scripts/measure_ros_bounds reads: "[ BOUND ] what: figure unit (bound < B)" for a bound set from
a measurement, "[ TIMING ] ...; catches ...)" for one that is no multiple of a measurement."""


def check_bound(test, what, figure, bound, unit):
    """figure < bound, printed as scripts/measure_ros_bounds reads it."""
    print("[ BOUND ] %s: %.6g %s (bound < %.6g)" % (what, figure, unit, bound))
    test.assertLess(figure, bound, what)


def check_timing(test, what, figure, bound, unit, catches):
    """figure < bound, a bound that is no multiple of a measurement: `catches` says what it
    is there for; printed as scripts/measure_ros_bounds reads it."""
    print("[ TIMING ] %s: %.6g %s (bound < %.6g; catches %s)" % (what, figure, unit, bound,
                                                                  catches))
    test.assertLess(figure, bound, what)
