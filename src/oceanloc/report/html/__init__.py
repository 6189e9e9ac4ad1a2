"""Offline HTML reports (plotly inlined, nothing fetched) and their KML map layers.

:func:`~oceanloc.report.html.sources.load_report` reads a survey journal or a JSON record into a
:class:`~oceanloc.report.html.model.Report`; :func:`~oceanloc.report.html.page.render_html` draws it;
:func:`~oceanloc.report.html.kml_layers.report_kml` writes its map layers as KML.
"""
