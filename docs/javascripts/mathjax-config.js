// MathJax 2, served from the site itself (javascripts/mathjax/, copied by docs/hooks/repository.py):
// the formulas of the pages (\( \) and \[ \] from pymdownx.arithmatex) and of the notebooks ($ $).
window.MathJax = {
  tex2jax: {
    inlineMath: [["\\(", "\\)"], ["$", "$"]],
    displayMath: [["\\[", "\\]"], ["$$", "$$"]],
    processEscapes: true,
    processEnvironments: true
  },
  "HTML-CSS": { availableFonts: ["TeX"], preferredFont: "TeX", imageFont: null },
  messageStyle: "none"
};
