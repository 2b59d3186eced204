"""The probe implementation's semantics (pure) and its CPU simulation over a plan."""
