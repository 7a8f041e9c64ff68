"""The bibliography of flexrv: one entry per cited work, under a short key.

Code and docstrings cite a work as ``:cite:`key``` (the Sphinx/sphinxcontrib-bibtex role,
so the syntax cannot be confused with the square-bracket units of docstrings), optionally
followed by a locator, e.g. ``:cite:`hamrock1994`, eq. 22.18``. Every key used anywhere in
the package must be in :data:`REFERENCES` (tests/test_references.py).

``docs/references.md`` is generated from this module (``python -m flexrv.references >
docs/references.md``) and checked to be identical, so the list lives in one place and is
installed with the package.

The five seed studies (``seed000`` ... ``seed004``) are the texts the project started from.
Their texts give no authors, venue or year; they are named here by their study (the title
where the text has one, otherwise the subject as the text states it). Entries marked
"not verified" are cited as the code cites them; their bibliographic details were not
checked against the source.
"""

from __future__ import annotations

import re

#: section title -> {key: citation (Markdown)}
SECTIONS: dict[str, dict[str, str]] = {
    "Seed studies (texts in the project's seed collection; no authors, venue or year given)": {
        "kelley1998ptc": "Kelley, C. T., Keyes, D. E. (1998). Convergence analysis of pseudo-transient "
        "continuation. *SIAM Journal on Numerical Analysis* 35(2), 508-523.",
        "seed000": "Seed study 000: transmission error of a rotary vector (RV) reducer with flexible, "
        "lubricated main bearings: a multi-physics dynamic model coupling the elastic deformation "
        "of the thin-walled angular-contact ball main bearings and their elastohydrodynamic (EHL) "
        "film with the reducer dynamics (RV reducer of total ratio 221; z_s = 12, z_p = 44, "
        "z_c = 59, z_rp = 60; input 9000 deg/s). Authors not given.",
        "seed001": "Seed study 001: influence of the flexibility and lubrication of thin-walled main bearings "
        "on the transmission error of RV reducers (same RV reducer of ratio 221 as seed000; "
        "ring deformation, oil-film thickness and pressure). Authors not given.",
        "seed002": "Seed study 002: dynamic characteristics of the rotary vector reducer by rigid-flexible "
        "coupling: parameterised 3-D model, flexible crankshaft (modal neutral file) in a "
        "multibody model, transmission error and its spectrum against the characteristic "
        "frequencies (RV-40E, 1215 r/min, 412 N m; Table 4). Authors not given.",
        "seed003": "Seed study 003: contact forces between the crankshaft and its rolling bearings in the "
        "RV-40E rotary vector reducer, by a combined dynamic (multibody) and static finite-element "
        "analysis. Authors not given.",
        "seed004": "Seed study 004: *Comprehensive Analysis of Meshing Stiffness and Zone Identification in "
        "Rotary Vector Reducers* — torsional stiffness model of the RV-40E, measured stiffness "
        "(0 to +-412 N m) and identification of the pins in mesh from it. Authors not given.",
    },
    "Books and papers": {
        "arnold2007": "Arnold, M., Brüls, O. (2007). Convergence of the generalized-alpha scheme for "
        "constrained mechanical systems. *Multibody System Dynamics* 18(2), 185-202.",
        "bates1988nonlinear": "Bates, D. M., Watts, D. G. (1988). *Nonlinear Regression Analysis and Its "
        "Applications*. Wiley, New York.",
        "blagojevic2011": "Blagojevic, M. et al. (2011). Two-stage cycloidal (RV-type) speed reducer. Cited in "
        "the code as *Mech. Mach. Theory* 2011; venue and title not verified.",
        "blanche1989": "Blanche, J. G., Yang, D. C. H. (1989). Cycloid drives with machining tolerances. "
        "*J. Mech. Transm. Autom. Des.* 111(3), 337-344.",
        "blank2020pymoo": "Blank, J., Deb, K. (2020). pymoo: Multi-objective optimization in Python. "
        "*IEEE Access* 8, 89497-89509.",
        "blevins1979": "Blevins, R. D. (1979). *Formulas for Natural Frequency and Mode Shape*. "
        "Van Nostrand Reinhold, New York.",
        "chen2008": "Chen et al. (2008). Cycloid-drive force analysis with initial clearances. As cited in the "
        "code; authors, title and venue not verified.",
        "chung1993": "Chung, J., Hulbert, G. M. (1993). A time integration algorithm for structural dynamics "
        "with improved numerical dissipation: the generalized-alpha method. *Journal of Applied Mechanics* "
        "60(2), 371-375.",
        "craig1968": "Craig, R. R., Bampton, M. C. C. (1968). Coupling of substructures for dynamic analyses. "
        "*AIAA Journal* 6(7), 1313-1319.",
        "deb2002nsga2": "Deb, K., Pratap, A., Agarwal, S., Meyarivan, T. (2002). A fast and elitist "
        "multiobjective genetic algorithm: NSGA-II. *IEEE Transactions on Evolutionary Computation* 6(2), 182-197.",
        "dowson1966": "Dowson, D., Higginson, G. R. (1966). *Elasto-hydrodynamic Lubrication: The Fundamentals "
        "of Roller and Gear Lubrication*. Pergamon Press, Oxford.",
        "george1973": "George, A. (1973). Nested dissection of a regular finite element mesh. "
        "*SIAM Journal on Numerical Analysis* 10(2), 345-363.",
        "grippo1986nonmonotone": "Grippo, L., Lampariello, F., Lucidi, S. (1986). A nonmonotone line search "
        "technique for Newton's method. *SIAM Journal on Numerical Analysis* 23(4), "
        "707-716.",
        "guyan1965": "Guyan, R. J. (1965). Reduction of stiffness and mass matrices. *AIAA Journal* 3(2), 380.",
        "hamrock1977": "Hamrock, B. J., Dowson, D. (1977). Isothermal elastohydrodynamic lubrication of point "
        "contacts, Part III: fully flooded results. *ASME Journal of Lubrication Technology* "
        "99(2), 264-276.",
        "hamrock1981": "Hamrock, B. J., Dowson, D. (1981). *Ball Bearing Lubrication: The Elastohydrodynamics "
        "of Elliptical Contacts*. Wiley, New York.",
        "hamrock1983": "Hamrock, B. J., Brewe, D. E. (1983). Simplified solution for stresses and deformations. "
        "*ASME Journal of Lubrication Technology* 105(2), 171-177.",
        "hamrock1994": "Hamrock, B. J. (1994). *Fundamentals of Fluid Film Lubrication*. McGraw-Hill, New York.",
        "harris2007": "Harris, T. A., Kotzalas, M. N. (2007). *Rolling Bearing Analysis*, 5th ed., vol. 1 "
        "*Essential Concepts of Bearing Technology* and vol. 2 *Advanced Concepts of Bearing "
        "Technology*. CRC Press (Taylor & Francis), Boca Raton.",
        "hetenyi1946": "Hetényi, M. (1946). *Beams on Elastic Foundation: Theory with Applications in the Fields "
        "of Civil and Mechanical Engineering*. University of Michigan Press, Ann Arbor.",
        "johnson1985": "Johnson, K. L. (1985). *Contact Mechanics*. Cambridge University Press.",
        "jones1960": "Jones, A. B. (1960). A general theory for elastically constrained ball and radial roller "
        "bearings under arbitrary load and speed conditions. *ASME Journal of Basic Engineering* "
        "82(2), 309-320.",
        "kahraman1991": "Kahraman, A., Singh, R. (1991). Interactions between time-varying mesh stiffness and "
        "clearance non-linearities in a geared system. *Journal of Sound and Vibration* 146(1), "
        "135-156.",
        "kahraman1994": "Kahraman, A. (1994). Planetary gear train dynamics. *ASME Journal of Mechanical Design* "
        "116(3), 713-720.",
        "karypis1998": "Karypis, G., Kumar, V. (1998). A fast and high quality multilevel scheme for "
        "partitioning irregular graphs. *SIAM Journal on Scientific Computing* 20(1), 359-392.",
        "li_lixing": "Li Lixing. Cycloid-pin gear load distribution with initial clearances (textbook method). "
        "As cited in the code; title, year and publisher not verified.",
        "lin1999": "Lin, J., Parker, R. G. (1999). Analytical characterization of the unique properties of "
        "planetary gear free vibration. *ASME Journal of Vibration and Acoustics* 121(3), 316-321.",
        "litvin2004": "Litvin, F. L., Fuentes, A. (2004). *Gear Geometry and Applied Theory*, 2nd ed. "
        "Cambridge University Press.",
        "love1929": "Love, A. E. H. (1929). The stress produced in a semi-infinite solid by pressure on part of "
        "the boundary. *Philosophical Transactions of the Royal Society of London A* 228, 377-420.",
        "lundberg1947": "Lundberg, G., Palmgren, A. (1947). Dynamic capacity of rolling bearings. *Acta "
        "Polytechnica, Mechanical Engineering Series* 1(3); and (1952) Dynamic capacity of "
        "roller bearings, ibid. 2(4).",
        "muller1982": "Müller, H. W. (1982). *Epicyclic Drive Trains: Analysis, Synthesis, and Applications*. "
        "Wayne State University Press, Detroit.",
        "nijenbanning1994": "Nijenbanning, G., Venner, C. H., Moes, H. (1994). Film thickness in "
        "elastohydrodynamically lubricated elliptic contacts. *Wear* 176(2), 217-229.",
        "palmgren1959": "Palmgren, A. (1959). *Ball and Roller Bearing Engineering*, 3rd ed. SKF Industries "
        "(S. H. Burbank & Co.), Philadelphia.",
        "pan1989": "Pan, P., Hamrock, B. J. (1989). Simple formulas for performance parameters used in "
        "elastohydrodynamically lubricated line contacts. *ASME Journal of Tribology* 111(2), "
        "246-251.",
        "parker2000": "Parker, R. G., Agashe, V., Vijayakar, S. M. (2000). Dynamic response of a planetary gear "
        "system using a finite element/contact mechanics model. *ASME Journal of Mechanical "
        "Design* 122(3), 304-310.",
        "roache1998": "Roache, P. J. (1998). *Verification and Validation in Computational Science and "
        "Engineering*. Hermosa Publishers, Albuquerque.",
        "roelands1966": "Roelands, C. J. A. (1966). *Correlational Aspects of the Viscosity-Temperature-"
        "Pressure Relationship of Lubricating Oils*. PhD thesis, Technische Hogeschool Delft.",
        "saad2003": "Saad, Y. (2003). *Iterative Methods for Sparse Linear Systems*, 2nd ed. SIAM, Philadelphia.",
        "timoshenko1970": "Timoshenko, S. P., Goodier, J. N. (1970). *Theory of Elasticity*, 3rd ed. "
        "McGraw-Hill, New York.",
        "venner2000": "Venner, C. H., Lubrecht, A. A. (2000). *Multilevel Methods in Lubrication*. Tribology "
        "Series 37, Elsevier, Amsterdam.",
        "yang2021": "Yang, Zhou, Chang, Chen (2021). *Mechanism and Machine Theory* 163, 104384. Title and "
        "first names not verified; not yet cited in the code.",
    },
    "Manufacturers' catalogues": {
        "nabtesco_rv": "Nabtesco Corporation. *Precision Reduction Gear RV: E Series / C Series / Original "
        "Series* (catalogue): rating table (rated torque, torsional rigidity, lost motion) and its "
        "definitions on the hysteresis curve of a torsion test with the input locked: rigidity as the "
        "slope between 50 % and 100 % of the rated torque, lost motion as the rotation at the midpoint of "
        "the curve's width between +-3 % of the rated torque, hysteresis loss. Edition not verified.",
        "nabtesco_rv_e_manual": "Nabtesco Corporation. *Precision Reduction Gear RV: E Series* (manual), "
        "appendix 'Design scheme of input gear', table 'Pass-through capacity of input gear' (p. 74): hole "
        "diameters d1, d2 and depths through which the input gear passes, and the speed ratios that allow "
        "it, per model (RV-40E / RV-30: d1 27 mm, d2 30 mm). Edition not verified.",
    },
    "Standards": {
        "iso76": "ISO 76:2006. Rolling bearings — Static load ratings. International Organization for "
        "Standardization, Geneva.",
        "iso281": "ISO 281:2007. Rolling bearings — Dynamic load ratings and rating life. International "
        "Organization for Standardization, Geneva.",
        "iso6336": "ISO 6336-1:2006. Calculation of load capacity of spur and helical gears — Part 1: Basic "
        "principles, introduction and general influence factors. International Organization for "
        "Standardization, Geneva.",
        "iso5593": "ISO 5593:2019. Rolling bearings — Vocabulary (radial internal clearance: the mean radial "
        "distance by which one ring can move relative to the other from one extreme position to the "
        "diametrically opposite one, the total play). International Organization for Standardization, Geneva.",
        "iso5753": "ISO 5753-1:2009. Rolling bearings — Internal clearance — Part 1: Radial internal clearance "
        "for radial bearings (groups C2, CN, C3, ...). International Organization for Standardization, Geneva.",
        "vdi2230": "VDI 2230 Blatt 1 (2015). Systematic calculation of highly stressed bolted joints — Joints "
        "with one cylindrical bolt (resilience of the bolt and of the clamped parts, including their bending "
        "resilience). Verein Deutscher Ingenieure, Düsseldorf.",
        "iso21771": "ISO 21771:2007. Gears — Cylindrical involute gears and gear pairs — Concepts and "
        "geometry. International Organization for Standardization, Geneva.",
    },
}

#: key -> citation (Markdown), all sections
REFERENCES: dict[str, str] = {k: v for sec in SECTIONS.values() for k, v in sec.items()}

#: a citation in code or docstrings: :cite:`key` (several keys separated by commas)
CITE_PATTERN = re.compile(r":cite:`([^`]+)`")


def cited_keys(text: str) -> list[str]:
    """Keys cited in ``text`` (``:cite:`a`` and ``:cite:`a,b```), in order of appearance."""
    return [k.strip() for group in CITE_PATTERN.findall(text) for k in group.split(",")]


def cite(key: str) -> str:
    """The citation of ``key`` (KeyError naming the known keys if it is missing)."""
    try:
        return REFERENCES[key]
    except KeyError:
        raise KeyError(f"unknown reference key {key!r}; known: {', '.join(sorted(REFERENCES))}") from None


def markdown() -> str:
    """The bibliography as Markdown (the content of docs/references.md)."""
    lines = [
        "# References",
        "",
        "Generated from `flexrv/references.py` (`python -m flexrv.references > docs/references.md`);",
        "edit that module, not this file. Code cites an entry as ``:cite:`key` ``.",
        "",
    ]
    for title, entries in SECTIONS.items():
        lines += [f"## {title}", ""]
        lines += [f"- **{key}** — {text}" for key, text in entries.items()]
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover
    print(markdown(), end="")
