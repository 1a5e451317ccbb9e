"""skidnav.models."""
