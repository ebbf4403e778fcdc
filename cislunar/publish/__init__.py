"""Publishing: claims and the status rule, comparison tables, figures, the notebook runner and the book."""
