"""The appendix formulas transcribed as printed (seed: ``../shared/seeds``), typos included.

Each entry carries its equation tag and the printed LaTeX. Formulas that are balanced
are also given as SymPy-buildable Python text in the symbols of
:mod:`derivations.rotations`, :mod:`derivations.singularity` and :mod:`derivations.variational`;
the rows of eq. (12) are kept as printed text (two of them do not parse: unbalanced
parentheses), and :mod:`derivations.audit` looks for the repairs that make them true.

Tags: ``App. 1.1 …`` for the unnumbered normal-form formulas, ``(n)`` for numbered ones.
"""
from __future__ import annotations

#: Δ(R) as printed at the start of App. 1.1.
DELTA = {
    "equation": "App. 1.1: Δ(R)",
    "latex": r"\varDelta(R)=r_{12}r_{31}+r_{21}r_{32}",
    "python": "r12*r31 + r21*r32",
}

DELTA_RPY = {
    "equation": "App. 1.1: Δ(φ,ϑ,ψ)",
    "latex": r"\sin\varphi\sin\vartheta\cos\psi+\sin\psi(\sin\varphi\cos^2\vartheta-\cos\varphi\sin^2\vartheta)",
    "python": "sin(phi)*sin(theta)*cos(psi) + sin(psi)*(sin(phi)*cos(theta)**2 - cos(phi)*sin(theta)**2)",
}

XI_ETA_ZETA = {
    "equation": "App. 1.1: Δ(ξ,η,ζ) = ξ sin φ + ηζ",
    "latex": r"\xi=\sin\vartheta\cos\psi,\ \eta=\sin\varphi\cos^2\vartheta-\cos\varphi\sin^2\vartheta,\ \zeta=\sin\psi;\ \varDelta=\xi\sin\varphi+\eta\zeta",
    "python": "xi*sin(phi) + eta*zeta",
}

IMPLICIT_PHI = {
    "equation": "App. 1.1: relation for φ(ξ,η,ζ)",
    "latex": r"-\sin\varphi+\eta+\frac{\xi^2(\cos\varphi+\sin\varphi)}{1-\zeta^2}=0",
    "python": "-sin(phi) + eta + xi**2*(cos(phi) + sin(phi))/(1 - zeta**2)",
}

DELTA_CUBIC = {
    "equation": "App. 1.1: Δ = ξ³(sin φ + cos φ)/(1−ζ²) + ξη + ηζ",
    "latex": r"\varDelta=\frac{\xi^3(\sin\varphi+\cos\varphi)}{1-\zeta^2}+\xi\eta+\eta\zeta",
    "python": "xi**3*(sin(phi) + cos(phi))/(1 - zeta**2) + xi*eta + eta*zeta",
}

NORMAL_FORM = {
    "equation": "App. 1.1: normal form f = z³ + xy",
    "latex": r"x=\xi+\zeta,\ y=\eta,\ z=\xi\left(\frac{\sin\varphi+\cos\varphi}{1-\zeta^2}\right)^{1/3};\ f(x,y,z)=z^3+xy",
    "python": "z**3 + x*y",
    "coordinates": ("xi + zeta", "eta", "xi*((sin(phi) + cos(phi))/(1 - zeta**2))**(S(1)/3)"),
}

EQ_4_5 = {
    "equation": "(4)–(5)",
    "latex": r"\frac{de(\theta)}{d\theta}=-\gamma e(\theta)\iff\frac{dl_T(\theta)}{d\theta}=-\gamma l_T(\theta),\ e=[l_T]",
}

EQ_6 = {
    "equation": "(6)",
    "latex": r"\frac{d\exp([l_T(\theta)])}{d\theta}\exp(-[l_T(\theta)])=\left[P(\theta)\frac{dl_T(\theta)}{d\theta}\right]",
}

#: The matrix P after eq. (7), as printed: the label says exp([l_T]).
P_AFTER_7 = {
    "equation": "(7): P(θ)",
    "latex": r"P(\theta)=\exp([l_T(\theta)])=\mathbb{I}_3+\frac{1-\cos\alpha}{\alpha^2}[l_T(\theta)]+\frac{\alpha-\sin\alpha}{\alpha^3}[l_T(\theta)]^2",
    "label": "exp",
    "rhs_coefficients": ("(1 - cos(alpha))/alpha**2", "(alpha - sin(alpha))/alpha**3"),
}

COS_ALPHA = {
    "equation": "(7): cos α",
    "latex": r"\cos\alpha=\frac{1}{2}(tr(R_TR_d^T)-1)",
}

EQ_8 = {
    "equation": "(8)",
    "latex": r"\frac{\partial s_t}{\partial t}=\frac{\partial L_t}{\partial\theta}u_\theta+L_t\frac{\partial u_\theta}{\partial\theta}+[L_tu_\theta]s_t",
}

EQ_9 = {
    "equation": "(9)",
    "latex": r"\frac{\partial s_t}{\partial t}=A_\theta s_t+B_\theta\frac{\partial u_\theta}{\partial\theta},\ A=Q+[Lu],\ B=L",
}

EQ_10_11 = {
    "equation": "(10)–(11)",
    "latex": r"J\,u'=\int_0^T\varPhi(T,t)B(t)u'(t)dt,\ J^{\#}l=B^T\varPhi^T(T,t)M^{-1}(T)l,\ \dot M=BB^T+AM+MA^T",
}

#: Eq. (12), row by row, as printed. ``e1T`` etc. are the row vectors e_iᵀ, ``H1``/``H2``
#: the skew matrices [r_1], [r_2] of the columns of R; juxtaposition written as ``*``.
EQ_12 = {
    "equation": "(12)",
    "latex": (r"Q=\frac{2}{\varDelta^2}\begin{bmatrix}"
              r"-r_{12}(m_1e_2^T-m_2e_3^T)[r_1]+r_{21}(m_1e_1^T+m_2e_3^T)[r_2]\\"
              r"r_{12}(m_1(e_2^T-m_2e_3^T)[r_1]-r_{21}(m_1e_1^T+m_2e_3^T)[r_2]\\"
              r"-r_{32}(m_1(e_2^T-m_2e_3^T)[r_1]-r_{31}(m_1e_1^T+m_2e_3^T)[r_2]\end{bmatrix}"),
    "factor": "2/Delta**2",
    "rows": (
        "-r12*(m1*e2T - m2*e3T)*H1 + r21*(m1*e1T + m2*e3T)*H2",
        "r12*(m1*(e2T - m2*e3T)*H1 - r21*(m1*e1T + m2*e3T)*H2",
        "-r32*(m1*(e2T - m2*e3T)*H1 - r31*(m1*e1T + m2*e3T)*H2",
    ),
    "m1": "r31*u1 - r32*u2",
    "m2": "r21*u1 + r12*u2",
    "Delta": "r12*r31 + r21*r32",
}

ALL = (DELTA, DELTA_RPY, XI_ETA_ZETA, IMPLICIT_PHI, DELTA_CUBIC, NORMAL_FORM, EQ_4_5, EQ_6,
       P_AFTER_7, COS_ALPHA, EQ_8, EQ_9, EQ_10_11, EQ_12)
