"""Wolf & Jones: information-based trajectory planning for a low-thrust observer (test cases 1 and 2)."""
