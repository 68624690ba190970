// MathJax 3, served from the site itself (javascripts/mathjax/, copied by docs/hooks/repository.py):
// the formulas of the pages (\( \) and \[ \] from pymdownx.arithmatex) and of the notebooks ($ $).
window.MathJax = {
  tex: {
    inlineMath: [["\\(", "\\)"], ["$", "$"]],
    displayMath: [["\\[", "\\]"], ["$$", "$$"]],
    processEscapes: true,
    processEnvironments: true
  },
  options: { enableMenu: false }
};
