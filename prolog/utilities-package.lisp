;;;; Package CRAM-UTILITIES (nickname CUT): lazy lists and variable bindings.

(defpackage :cram-utilities
  (:nicknames :cut)
  (:use :cl)
  (:export
   ;; lazy lists
   #:lazy-list #:cont #:next #:finish #:make-lazy-list #:lazy-list-p #:lazy-tail-p
   #:lazy-car #:lazy-cdr #:lazy-mapcar #:lazy-mapcan #:lazy-filter #:lazy-append
   #:lazy-take #:lazy-elt #:lazy-fold #:lazy-dolist #:force-ll #:expanded-length
   #:lazy-skip #:lazy-flatten #:lazy-rests #:lazy-list-type-error
   #:with-lazy-list-dynamic-environment #:delay #:delay-p #:force
   ;; pattern matching
   #:pat-match #:pat-match-p #:match-segvar #:with-pat-vars-bound #:bindings-equal
   #:patterns-eq #:is-unnamed-var #:is-segvar #:is-segform #:var-name #:gen-var #:is-genvar
   #:map-tree #:?_ #:!?_
   ;; threads and strings
   #:current-thread #:spawn-thread #:spawn-threads #:join-thread #:kill-thread
   #:thread-alive-p #:replace-all
   ;; bindings
   #:is-var #:is-anonymous-var #:var-value #:is-bound #:is-ground #:add-bdg
   #:unify #:unify-p #:substitute-vars #:vars-in #:rename-vars
   #:with-vars-bound #:with-vars-strictly-bound #:unbound-variable-error
   #:unbound-variable-error-variable))
