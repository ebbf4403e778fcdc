"""Claims of Greaves & Scheeres 2021, one module per notebook (chapter): declarations only, judged in the notebooks."""
