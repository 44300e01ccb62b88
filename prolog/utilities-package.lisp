;;;; Package CRAM-UTILITIES (nickname CUT): lazy lists and variable bindings.

(defpackage :cram-utilities
  (:nicknames :cut)
  (:use :cl)
  (:export
   ;; lazy lists
   #:lazy-list #:cont #:next #:finish #:make-lazy-list #:lazy-list-p #:lazy-tail-p
   #:lazy-car #:lazy-cdr #:lazy-mapcar #:lazy-mapcan #:lazy-filter #:lazy-append
   #:lazy-take #:lazy-elt #:lazy-fold #:lazy-dolist #:force-ll #:expanded-length
   ;; bindings
   #:is-var #:is-anonymous-var #:var-value #:is-bound #:is-ground #:add-bdg
   #:unify #:substitute-vars #:vars-in #:rename-vars
   #:with-vars-bound #:with-vars-strictly-bound #:unbound-variable-error
   #:unbound-variable-error-variable))
