;;;; Package CRAM-WALKER (nickname WALKER): expanding plans into plan trees.

(defpackage :cram-walker
  (:nicknames :walker)
  (:use :cl)
  (:export
   #:plan-tree-node #:make-plan-tree-node #:plan-tree-node-p #:plan-tree-node-sexp
   #:plan-tree-node-parent #:plan-tree-node-children #:plan-tree-node-path
   #:find-plan-node #:expand-plan #:walk-with-tag-handler
   #:register-plan #:plan-definition))
