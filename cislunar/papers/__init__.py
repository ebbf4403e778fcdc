"""One package per paper: its scenarios, studies, claims and figures.  Papers never import each other."""
