"""Time parameterisation of joint paths within velocity and acceleration limits."""
