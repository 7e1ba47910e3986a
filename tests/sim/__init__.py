"""The cloth simulator: physics checks against analytic answers."""
