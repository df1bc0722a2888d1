"""What the results are checked against: closed forms, the OpenGeoSys peer problem
as a case, and ``xfemslip verify``.

Modules:

- ``closed_form``: the frictional straight crack and the slip window;
- ``closed_form_depletion``: uniaxial strain and the offset-reservoir fault
  under depletion;
- ``peer``: the OpenGeoSys peer problem as an xfemslip case;
- ``verify``: the verification problems of ``xfemslip verify``;
- ``report``: the table, CSV file and plot of ``xfemslip verify``.

The subpackage imports nothing itself: import the module you need (``from
xfemslip.reference.closed_form import ...``)."""

__all__ = ["closed_form", "closed_form_depletion", "peer", "report", "verify"]
