"""What continuous wheel speeds buy: episode traces, their metrics and the wheel-speed
comparison."""
