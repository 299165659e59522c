"""What a fit minimises: the losses (``losses.py``), the data of a fit as padded arrays with its residuals and the
normal equations accumulated in one pass (``problem.py``), and a model's Jacobian factored as a per-sample basis
times coefficients (``jacobian.py``)."""
