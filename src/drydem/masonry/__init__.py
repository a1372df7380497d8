"""The masonry domain: brick layouts and wall files, the competition's brief, the built-in walls
(``designs``), studies (``studies``) and published data (``published``)."""
